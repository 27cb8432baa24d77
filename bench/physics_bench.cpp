// manibench_physics_bench: environment steps per second of manibench's
// Simbody scene and of MuJoCo 2.2.2 on the same scenes, side by side.
//
// An environment step is 5 control ticks of 10 ms (ManiSkill's 20 Hz agent,
// 100 Hz controller). Each scene is built from one bench::Model as URDF for
// manibench::Scene and as MJCF for MuJoCo (timestep 2 ms by default, 5
// mj_steps per tick). Per scene and engine: settle, warm up, then several
// measurement windows, alternating between the engines so that both see
// the same machine noise; the table gives the median. Every scene is
// checked for physical sanity in both engines; a failed check makes the
// exit status 1 (a benchmark of a broken scene measures nothing). Speed is
// reported, never asserted.
#include <mujoco/mujoco.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "bench_engines.hpp"
#include "bench_model.hpp"
#include "bench_scenes.hpp"
#include "manibench/scene.hpp"

namespace manibench::bench {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

struct Options {
  double warmup = 2.0;   // wall seconds per engine and scene
  double seconds = 2.0;  // wall seconds per measurement window
  int repeats = 5;       // measurement windows per engine and scene
  double mujoco_dt = 0.002;
  std::string mujoco_integrator;  // overrides every scene's MuJoCo integrator
  std::string integrator;  // overrides every scene's Simbody integrator
  double accuracy = 0;     // overrides PhysicsSettings::accuracy if > 0
  double fixed_step = 0;   // overrides PhysicsSettings::fixed_step if > 0
  std::vector<std::string> scenes;  // name prefixes; empty: all
  bool verbose = false;
  bool list = false;
  bool run_unsupported = false;  // run scenes whose contact is missing
  bool strict = false;           // a scene not supported yet is a failure
  std::string write_models;      // directory for the generated URDF/MJCF
};

void printUsage(std::FILE* out) {
  std::fprintf(out,
               "usage: manibench_physics_bench [options]\n"
               "  --scene NAME[,NAME...]  run only scenes whose name starts with NAME\n"
               "                          (arm10, drawer, boxes10, boxes100, spheres10,\n"
               "                          spheres100, stacks100; 'boxes' selects boxes10\n"
               "                          and boxes100)\n"
               "  --seconds S             measurement window, wall seconds (default 2)\n"
               "  --warmup S              warm-up per engine, wall seconds (default 2)\n"
               "  --repeats N             windows per engine; the median is reported (default 5)\n"
               "  --quick                 smoke test: --warmup 0 --seconds 0.2 --repeats 1\n"
               "  --integrator NAME       Simbody integrator for every scene: cpodes,\n"
               "                          rk_merson or semi_explicit_euler (default: per scene)\n"
               "  --accuracy A            Simbody integrator accuracy (default 1e-2)\n"
               "  --fixed-step H          Simbody semi_explicit_euler step (default 5e-4 s)\n"
               "  --mujoco-dt DT          MuJoCo timestep, must divide 10 ms (default 0.002)\n"
               "  --mujoco-integrator I   Euler or implicit for every scene (default: per scene)\n"
               "  --verbose               print every measurement window\n"
               "  --run-unsupported       run scenes needing contact manibench lacks anyway\n"
               "  --strict                count scenes manibench cannot run yet as failures\n"
               "  --write-models DIR      write each selected scene's URDF and MJCF to DIR\n"
               "                          and exit\n"
               "  --list                  list the scenes and exit\n"
               "Exit status: 0 if every scene run is physically sane in both engines, 1 if\n"
               "not (or, with --strict, if a scene could not run), 2 on bad usage.\n");
}

bool parseNumber(const char* text, double& value) {
  char* end = nullptr;
  value = std::strtod(text, &end);
  return end != text && *end == '\0' && std::isfinite(value);
}

// Returns false (after printing why) on bad usage.
bool parseOptions(int argc, char** argv, Options& options) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&](double& out, double min) {
      if (i + 1 >= argc || !parseNumber(argv[i + 1], out) || out < min) {
        std::fprintf(stderr, "manibench_physics_bench: %s needs a number >= %g\n", arg.c_str(), min);
        return false;
      }
      ++i;
      return true;
    };
    auto text = [&](std::string& out) {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "manibench_physics_bench: %s needs a value\n", arg.c_str());
        return false;
      }
      out = argv[++i];
      return true;
    };
    double number = 0;
    if (arg == "--help" || arg == "-h") {
      printUsage(stdout);
      std::exit(0);
    } else if (arg == "--seconds") {
      if (!value(options.seconds, 0)) return false;
    } else if (arg == "--warmup") {
      if (!value(options.warmup, 0)) return false;
    } else if (arg == "--repeats") {
      if (!value(number, 1)) return false;
      options.repeats = static_cast<int>(number);
    } else if (arg == "--quick") {
      options.warmup = 0;
      options.seconds = 0.2;
      options.repeats = 1;
    } else if (arg == "--integrator") {
      if (!text(options.integrator)) return false;
    } else if (arg == "--accuracy") {
      if (!value(options.accuracy, 1e-12)) return false;
    } else if (arg == "--fixed-step") {
      if (!value(options.fixed_step, 1e-9)) return false;
    } else if (arg == "--mujoco-integrator") {
      if (!text(options.mujoco_integrator)) return false;
    } else if (arg == "--mujoco-dt") {
      if (!value(options.mujoco_dt, 1e-6)) return false;
    } else if (arg == "--scene") {
      std::string list;
      if (!text(list)) return false;
      std::stringstream s(list);
      for (std::string name; std::getline(s, name, ',');)
        if (!name.empty()) options.scenes.push_back(name);
    } else if (arg == "--verbose") {
      options.verbose = true;
    } else if (arg == "--list") {
      options.list = true;
    } else if (arg == "--strict") {
      options.strict = true;
    } else if (arg == "--run-unsupported") {
      options.run_unsupported = true;
    } else if (arg == "--write-models") {
      if (!text(options.write_models)) return false;
    } else {
      std::fprintf(stderr, "manibench_physics_bench: unknown option '%s'\n", arg.c_str());
      printUsage(stderr);
      return false;
    }
  }
  return true;
}

bool isSelected(const Options& options, const std::string& name) {
  if (options.scenes.empty()) return true;
  for (const std::string& prefix : options.scenes)
    if (name.compare(0, prefix.size(), prefix) == 0) return true;
  return false;
}

PhysicsSettings makeSettings(const BenchScene& scene, const Options& options) {
  PhysicsSettings settings;
  settings.integrator =
      parseIntegrator(options.integrator.empty() ? scene.integrator : options.integrator);
  if (options.accuracy > 0) settings.accuracy = options.accuracy;
  if (options.fixed_step > 0) settings.fixed_step = options.fixed_step;
  // MuJoCo has one friction coefficient: use it for both of Simbody's.
  settings.default_material.static_friction = scene.model.friction;
  settings.default_material.dynamic_friction = scene.model.friction;
  return settings;
}

std::string describeIntegrator(const PhysicsSettings& settings) {
  std::ostringstream s;
  s << getIntegratorName(settings.integrator);
  if (settings.integrator == Integrator::SemiExplicitEuler)
    s << " h=" << settings.fixed_step;
  else
    s << " acc=" << settings.accuracy;
  return s.str();
}

// Does manibench's scene make boxes touch boxes? A 10 cm box dropped 1 mm
// onto a fixed slab: without box-box contact it falls through.
bool probeBoxBoxContact() {
  try {
    Model model;
    Articulation slab;
    slab.name = "slab";
    slab.root_position = Eigen::Vector3d(0, 0, 0.05);
    Link slab_link;
    slab_link.name = "body";
    slab_link.shapes.push_back(Shape::box(Eigen::Vector3d(0.2, 0.2, 0.05)));
    slab.links.push_back(slab_link);
    Articulation box;
    box.name = "box";
    box.fixed_base = false;
    box.root_position = Eigen::Vector3d(0, 0, 0.151);
    Link box_link;
    box_link.name = "body";
    box_link.inertia = Eigen::Vector3d::Constant(1.0 / 600);
    box_link.shapes.push_back(Shape::box(Eigen::Vector3d::Constant(0.05)));
    box.links.push_back(box_link);
    model.articulations = {slab, box};
    auto engine = makeManibenchEngine(model, PhysicsSettings());
    for (int i = 0; i < 30; ++i) engine->tick();
    return std::abs(engine->getRootPosition(1).z() - 0.15) < 5e-3;
  } catch (const std::exception&) {
    return false;
  }
}

// One engine running one scene: the scripted episodes, the checks, timing.
class Runner {
 public:
  Runner(const BenchScene& scene, std::unique_ptr<Engine> engine)
      : scene_(scene), engine_(std::move(engine)), targets_(scene.model.drives.size()) {}

  // Untimed: simulate the scene's settling time and check the result.
  void settle() {
    while (ok() && ticks_ * kControlDt < scene_.settle_time - 1e-9) envStep();
    if (scene_.episode_ticks == 0) check();
  }

  // Env steps per second over at least `seconds` of wall time (at least one
  // step); NaN if the engine failed.
  double measure(double seconds) {
    if (!ok()) return std::nan("");
    long steps = 0;
    const Clock::time_point start = Clock::now();
    double elapsed = 0;
    do {
      envStep();
      ++steps;
      elapsed = secondsSince(start);
    } while (ok() && elapsed < seconds);
    if (scene_.episode_ticks == 0) check();
    return ok() ? steps / elapsed : std::nan("");
  }

  // Untimed: runs to the end of the current episode so that episodic scenes
  // are checked at least once.
  void finish() {
    if (scene_.episode_ticks == 0) return;
    const long target = episodes_ + 1;
    while (ok() && episodes_ < target) envStep();
  }

  bool ok() const { return failure_.empty(); }
  // "" if every check so far passed and the engine reported nothing wrong.
  std::string getProblem() const {
    std::string problem = failure_.empty() ? problem_ : failure_;
    const std::string engine_problems = engine_->getProblems();
    if (!engine_problems.empty()) problem += (problem.empty() ? "" : "; ") + engine_problems;
    return problem;
  }
  long getEpisodes() const { return episodes_; }

 private:
  void envStep() {
    try {
      for (int i = 0; i < kTicksPerEnvStep && ok(); ++i) tick();
    } catch (const std::exception& e) {
      failure_ = std::string("simulation failed: ") + e.what();
    }
  }

  void tick() {
    if (scene_.policy) {
      scene_.policy(episode_tick_ * kControlDt, targets_);
      engine_->setTargets(targets_);
    }
    engine_->tick();
    ++ticks_;
    if (scene_.episode_ticks > 0 && ++episode_tick_ == scene_.episode_ticks) {
      check();
      engine_->reset();
      episode_tick_ = 0;
      ++episodes_;
    }
  }

  void check() {
    if (!scene_.check || !problem_.empty()) return;
    problem_ = scene_.check(*engine_);
    if (!problem_.empty()) {
      std::ostringstream where;
      where << " (at t=" << engine_->getTime() << " s";
      if (scene_.episode_ticks > 0) where << ", episode " << episodes_ + 1;
      where << ")";
      problem_ += where.str();
    }
  }

  const BenchScene& scene_;
  std::unique_ptr<Engine> engine_;
  std::vector<DriveTarget> targets_;
  long ticks_ = 0;
  long episodes_ = 0;
  int episode_tick_ = 0;
  std::string problem_;
  std::string failure_;
};

double median(std::vector<double> values) {
  values.erase(std::remove_if(values.begin(), values.end(), [](double v) { return !std::isfinite(v); }),
               values.end());
  if (values.empty()) return std::nan("");
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

struct Row {
  std::string scene;
  std::string integrator;
  std::vector<double> simbody, mujoco;  // env/s per window
  std::string status = "ok";            // "ok", "not supported yet", "FAIL"
  std::vector<std::string> notes;
};

std::string formatRate(const std::vector<double>& rates) {
  const double m = median(rates);
  if (!std::isfinite(m)) return "-";
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, m >= 100 ? "%.0f" : "%.1f", m);
  std::string text = buffer;
  if (rates.size() > 1) {
    const auto [lo, hi] = std::minmax_element(rates.begin(), rates.end());
    std::snprintf(buffer, sizeof buffer, m >= 100 ? " (%.0f-%.0f)" : " (%.1f-%.1f)", *lo, *hi);
    text += buffer;
  }
  return text;
}

std::string formatRatio(const Row& row) {
  const double ratio = median(row.mujoco) / median(row.simbody);
  if (!std::isfinite(ratio)) return "-";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.2fx", ratio);
  return buffer;
}

Row runScene(const BenchScene& scene, const Options& options, bool box_box) {
  Row row;
  row.scene = scene.name;
  const PhysicsSettings settings = makeSettings(scene, options);
  row.integrator = describeIntegrator(settings);
  if (scene.needs_box_box && !box_box && !options.run_unsupported) {
    row.status = "not supported yet";
    row.notes.push_back("needs box-box contact, which manibench's scene does not simulate yet");
    return row;
  }
  std::fprintf(stderr, "manibench_physics_bench: %s ...\n", scene.name.c_str());

  std::unique_ptr<Runner> engines[2];
  const char* names[2] = {"manibench/Simbody", "MuJoCo"};
  try {
    engines[0] = std::make_unique<Runner>(scene, makeManibenchEngine(scene.model, settings));
    MujocoSettings mujoco;
    mujoco.mjcf.timestep = options.mujoco_dt;
    mujoco.mjcf.integrator =
        options.mujoco_integrator.empty() ? scene.mujoco_integrator : options.mujoco_integrator;
    engines[1] = std::make_unique<Runner>(scene, makeMujocoEngine(scene.model, mujoco));
  } catch (const std::exception& e) {
    row.status = "FAIL";
    row.notes.push_back(std::string("cannot build the scene: ") + e.what());
    return row;
  }

  for (auto& engine : engines) {
    engine->settle();
    engine->measure(options.warmup);
  }
  for (int r = 0; r < options.repeats; ++r) {
    row.simbody.push_back(engines[0]->measure(options.seconds));
    row.mujoco.push_back(engines[1]->measure(options.seconds));
    if (options.verbose)
      std::fprintf(stderr, "  window %d: manibench %.1f env/s, MuJoCo %.1f env/s\n", r + 1,
                   row.simbody.back(), row.mujoco.back());
  }
  for (int e = 0; e < 2; ++e) {
    engines[e]->finish();
    const std::string problem = engines[e]->getProblem();
    if (!problem.empty()) {
      row.status = "FAIL";
      row.notes.push_back(std::string(names[e]) + ": " + problem);
    }
  }
  if (scene.episode_ticks > 0) {
    std::ostringstream note;
    note << "episodes checked: manibench " << engines[0]->getEpisodes() << ", MuJoCo "
         << engines[1]->getEpisodes();
    row.notes.push_back(note.str());
  }
  return row;
}

void printTable(const std::vector<Row>& rows) {
  std::printf("\n%-11s %-28s %-20s %-20s %-15s %s\n", "scene", "Simbody integrator", "Simbody env/s",
              "MuJoCo env/s", "MuJoCo/Simbody", "sanity");
  for (const Row& row : rows)
    std::printf("%-11s %-28s %-20s %-20s %-15s %s\n", row.scene.c_str(), row.integrator.c_str(),
                formatRate(row.simbody).c_str(), formatRate(row.mujoco).c_str(),
                formatRatio(row).c_str(), row.status.c_str());
  bool any_note = false;
  for (const Row& row : rows)
    for (const std::string& note : row.notes) {
      if (!any_note) std::printf("\n");
      any_note = true;
      std::printf("%s: %s\n", row.scene.c_str(), note.c_str());
    }
}

bool writeFile(const std::string& path, const std::string& text) {
  std::ofstream file(path);
  file << text;
  if (!file.good()) {
    std::fprintf(stderr, "manibench_physics_bench: cannot write %s\n", path.c_str());
    return false;
  }
  std::printf("%s\n", path.c_str());
  return true;
}

bool writeModels(const BenchScene& scene, const Options& options) {
  MjcfOptions mjcf;
  mjcf.timestep = options.mujoco_dt;
  mjcf.integrator =
      options.mujoco_integrator.empty() ? scene.mujoco_integrator : options.mujoco_integrator;
  const std::string base = options.write_models + "/" + scene.name;
  if (!writeFile(base + ".xml", toMjcf(scene.model, mjcf))) return false;
  // Free-body scenes repeat one URDF; write the first of each name pattern.
  for (std::size_t a = 0; a < scene.model.articulations.size() && a < 2; ++a) {
    const Articulation& art = scene.model.articulations[a];
    if (!writeFile(base + "." + art.name + ".urdf", toUrdf(art))) return false;
  }
  return true;
}

int run(int argc, char** argv) {
  Options options;
  if (!parseOptions(argc, argv, options)) return 2;
  std::vector<BenchScene> scenes = makeScenes();
  if (options.list) {
    for (const BenchScene& scene : scenes)
      std::printf("%-11s %s\n", scene.name.c_str(), scene.description.c_str());
    return 0;
  }
  bool any = false;
  for (const BenchScene& scene : scenes) any = any || isSelected(options, scene.name);
  if (!any) {
    std::fprintf(stderr, "manibench_physics_bench: no scene matches --scene; --list shows them\n");
    return 2;
  }

  if (!options.write_models.empty()) {
    for (const BenchScene& scene : scenes)
      if (isSelected(options, scene.name) && !writeModels(scene, options))
        return 1;
    return 0;
  }

  const bool box_box = probeBoxBoxContact();
  std::printf("manibench physics benchmark: env step = %d control ticks of %g ms; MuJoCo %s, "
              "timestep %g ms\n",
              kTicksPerEnvStep, kControlDt * 1e3, mj_versionString(), options.mujoco_dt * 1e3);
  std::printf("per scene and engine: settle, %g s warm-up, %d window(s) of %g s (median, "
              "[min-max]); manibench box-box contact: %s\n",
              options.warmup, options.repeats, options.seconds, box_box ? "yes" : "no");
  std::fflush(stdout);

  std::vector<Row> rows;
  for (const BenchScene& scene : scenes)
    if (isSelected(options, scene.name)) rows.push_back(runScene(scene, options, box_box));
  printTable(rows);

  std::printf("\nMuJoCo/Simbody: MuJoCo's median env/s divided by manibench's (how many times "
              "faster MuJoCo is).\n");
  for (const Row& row : rows)
    if ((row.scene == "boxes100" || row.scene == "stacks100") && row.status == "ok") {
      const double ratio = median(row.mujoco) / median(row.simbody);
      std::printf("box pile (%s): MuJoCo/Simbody = %.2fx, target <= 5x: %s\n", row.scene.c_str(),
                  ratio, ratio <= 5 ? "met" : "NOT met");
    }
  bool sane = true;
  for (const Row& row : rows)
    sane = sane && row.status != "FAIL" && (!options.strict || row.status == "ok");
  return sane ? 0 : 1;
}

}  // namespace
}  // namespace manibench::bench

int main(int argc, char** argv) {
  try {
    return manibench::bench::run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "manibench_physics_bench: %s\n", e.what());
    return 1;
  }
}
