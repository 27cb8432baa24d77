// manibench_physics_bench: environment steps per second of manibench's
// Simbody scene and of MuJoCo 2.2.2 on the same scenes, side by side.
//
// An environment step is 5 control ticks of 10 ms (ManiSkill's 20 Hz agent,
// 100 Hz controller). Each scene is built from one bench::Model as URDF for
// manibench::Scene and as MJCF for MuJoCo (timestep 2 ms by default, 5
// mj_steps per tick), except cabinet_random, the twin of the real
// OpenCabinetDrawer-v0 environment (cabinet_twin.hpp). Per scene and engine: settle, warm up, then several
// measurement windows, alternating between the engines so that both see
// the same machine noise; the table gives the median, and manibench's
// integrator work per env step (load-independent). Every scene is
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
#include "bench_run.hpp"
#include "bench_scenes.hpp"
#include "manibench/scene.hpp"
#include "model_run.hpp"

namespace manibench::bench {
namespace {

struct Options {
  double warmup = 2.0;   // wall seconds per engine and scene
  double seconds = 2.0;  // wall seconds per measurement window
  int repeats = 5;       // measurement windows per engine and scene
  RunOptions run;        // overrides of the scenes' own settings
  bool quick = false;
  std::vector<std::string> scenes;  // name prefixes; empty: all
  bool verbose = false;
  bool list = false;
  bool run_unsupported = false;  // run scenes whose contact is missing
  bool strict = false;           // a scene not supported yet is a failure
  std::string write_models;      // directory for the generated URDF/MJCF
  // An accuracy reference for manibench: "INTEGRATOR[:VALUE]" (VALUE: the
  // accuracy of cpodes/rk_merson, the step of the fixed-step ones), run
  // untimed on the first `reference_episodes` episodes of episodic scenes.
  std::string reference;
  int reference_episodes = 3;
};

void printUsage(std::FILE* out) {
  std::fprintf(out,
               "usage: manibench_physics_bench [options]\n"
               "  --scene NAME[,NAME...]  run only scenes whose name starts with NAME\n"
               "                          (arm10, drawer, arm10_random, drawer_random,\n"
               "                          boxes10, boxes100, spheres10, spheres100,\n"
               "                          stacks100, cabinet_random; 'boxes' selects\n"
               "                          boxes10 and boxes100, 'drawer' drawer and\n"
               "                          drawer_random)\n"
               "  --seconds S             measurement window, wall seconds (default 2)\n"
               "  --warmup S              warm-up per engine, wall seconds (default 2)\n"
               "  --repeats N             windows per engine; the median is reported (default 5)\n"
               "  --quick                 smoke test: --warmup 0 --seconds 0.2 --repeats 1\n"
               "  --integrator NAME       Simbody integrator for every scene: cpodes,\n"
               "                          rk_merson or semi_explicit_euler (default: per scene)\n"
               "  --accuracy A            Simbody integrator accuracy (default 1e-2)\n"
               "  --fixed-step H          Simbody semi_explicit_euler step (default 5e-4 s)\n"
               "  --implicit-step H       Simbody implicit_euler step (default 2e-3 s)\n"
               "  --reference I[:V]       accuracy: also run manibench with integrator I\n"
               "                          (V: its accuracy, or its step for the fixed-step\n"
               "                          ones) on the first episodes of each episodic scene\n"
               "                          and print how far the episode ends differ\n"
               "  --reference-episodes N  episodes compared with --reference (default 3)\n"
               "  --mujoco-dt DT          MuJoCo timestep, must divide 10 ms (default 0.002)\n"
               "  --twin-object ID        cabinet_random: the object (default: the first\n"
               "                          train object, 2000_link_0)\n"
               "  --twin-seed N           cabinet_random: the reset seed (default 0)\n"
               "  --twin-steps N          cabinet_random: env steps per episode (default: the\n"
               "                          task's 200; 10 with --quick)\n"
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
      options.quick = true;
    } else if (arg == "--twin-object") {
      if (!text(options.run.twin_object)) return false;
    } else if (arg == "--twin-seed") {
      if (!value(number, 0)) return false;
      options.run.twin_seed = static_cast<std::uint64_t>(number);
    } else if (arg == "--twin-steps") {
      if (!value(number, 1)) return false;
      options.run.twin_episode_steps = static_cast<int>(number);
    } else if (arg == "--integrator") {
      if (!text(options.run.integrator)) return false;
    } else if (arg == "--accuracy") {
      if (!value(options.run.accuracy, 1e-12)) return false;
    } else if (arg == "--fixed-step") {
      if (!value(options.run.fixed_step, 1e-9)) return false;
    } else if (arg == "--implicit-step") {
      if (!value(options.run.implicit_step, 1e-9)) return false;
    } else if (arg == "--reference") {
      if (!text(options.reference)) return false;
    } else if (arg == "--reference-episodes") {
      if (!value(number, 1)) return false;
      options.reference_episodes = static_cast<int>(number);
    } else if (arg == "--mujoco-integrator") {
      if (!text(options.run.mujoco_integrator)) return false;
    } else if (arg == "--mujoco-dt") {
      if (!value(options.run.mujoco_dt, 1e-6)) return false;
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
  // A short twin episode keeps the smoke test within seconds.
  if (options.quick && options.run.twin_episode_steps == 0) options.run.twin_episode_steps = 10;
  return true;
}

bool isSelected(const Options& options, const std::string& name) {
  if (options.scenes.empty()) return true;
  for (const std::string& prefix : options.scenes)
    if (name.compare(0, prefix.size(), prefix) == 0) return true;
  return false;
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

// "end of episodes 1-3, manibench vs MuJoCo: largest joint difference
// 0.0012" over the episodes both engines completed; sets `worst` (NaN if
// there were none).
std::string compareEpisodeEnds(const SceneRun& a, const SceneRun& b, double& worst,
                               const std::string& versus = "manibench vs MuJoCo") {
  const std::size_t n = std::min(a.getEpisodeEnds().size(), b.getEpisodeEnds().size());
  worst = std::nan("");
  if (n == 0) return {};
  worst = 0;
  for (std::size_t e = 0; e < n; ++e) {
    const Eigen::VectorXd& x = a.getEpisodeEnds()[e];
    const Eigen::VectorXd& y = b.getEpisodeEnds()[e];
    if (x.size() == 0 || x.size() != y.size()) return {};
    const double difference = (x - y).cwiseAbs().maxCoeff();
    worst = std::isfinite(difference) ? std::max(worst, difference) : difference;
  }
  const std::string episodes = n == 1 ? "episode 1" : "episodes 1-" + std::to_string(n);
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.3g", worst);
  return "end of " + episodes + ", " + versus + ": largest joint difference " + buffer;
}

// manibench's integrator work per env step: load-independent, unlike the
// timings.
std::string describeWork(const SceneRun& run) {
  const IntegratorStatistics s = run.getIntegratorStatistics();
  const double n = static_cast<double>(run.getEnvSteps());
  if (n <= 0 || s.realizations == 0) return {};
  char buffer[200];
  std::snprintf(buffer, sizeof buffer, "manibench per env step: %.1f integrator steps, ", s.steps / n);
  std::string text = buffer;
  if (s.jacobians > 0) {  // implicit integrators only
    std::snprintf(buffer, sizeof buffer, "%.1f Newton iterations, %.2f Jacobians, ",
                  s.iterations / n, s.jacobians / n);
    text += buffer;
  }
  std::snprintf(buffer, sizeof buffer, "%.1f evaluations of the dynamics (%ld env steps)",
                s.realizations / n, run.getEnvSteps());
  return text + buffer;
}

// --reference: the run's options with the reference integrator.
RunOptions makeReferenceOptions(const Options& options) {
  RunOptions reference = options.run;
  const std::size_t colon = options.reference.find(':');
  reference.integrator = options.reference.substr(0, colon);
  if (colon == std::string::npos) return reference;
  double value = 0;
  if (!parseNumber(options.reference.c_str() + colon + 1, value) || !(value > 0))
    throw std::invalid_argument("--reference " + options.reference + ": the value after ':' must be positive");
  switch (parseIntegrator(reference.integrator)) {
    case Integrator::ImplicitEuler: reference.implicit_step = value; break;
    case Integrator::SemiExplicitEuler: reference.fixed_step = value; break;
    case Integrator::CPodes:
    case Integrator::RkMerson: reference.accuracy = value; break;
  }
  return reference;
}

// How far manibench's episode ends lie from the reference integrator's on
// the same commands: the integration error of the timed settings.
std::string compareWithReference(const BenchScene& scene, const Options& options,
                                 const SceneRun& measured) {
  try {
    const RunOptions reference_options = makeReferenceOptions(options);
    SceneRuns runs = scene.make_runs ? scene.make_runs(reference_options)
                                     : makeModelRuns(scene, reference_options);
    SceneRun& reference = *runs.manibench;
    reference.settle();
    reference.runEpisodes(std::min<long>(options.reference_episodes, measured.getEpisodes()));
    if (!reference.ok()) return "reference " + runs.integrator + ": " + reference.getProblem();
    double worst = 0;
    return compareEpisodeEnds(measured, reference, worst, "manibench vs " + runs.integrator);
  } catch (const std::exception& e) {
    return std::string("reference: ") + e.what();
  }
}

Row runScene(const BenchScene& scene, const Options& options, bool box_box) {
  Row row;
  row.scene = scene.name;
  if (!scene.make_runs) row.integrator = describeIntegrator(makeModelSettings(scene, options.run));
  if (scene.needs_box_box && !box_box && !options.run_unsupported) {
    row.status = "not supported yet";
    row.notes.push_back("needs box-box contact, which manibench's scene does not simulate yet");
    return row;
  }
  std::fprintf(stderr, "manibench_physics_bench: %s ...\n", scene.name.c_str());

  SceneRuns runs;
  try {
    runs = scene.make_runs ? scene.make_runs(options.run) : makeModelRuns(scene, options.run);
  } catch (const std::exception& e) {
    row.status = "FAIL";
    row.notes.push_back(std::string("cannot build the scene: ") + e.what());
    return row;
  }
  row.integrator = runs.integrator;
  row.notes = runs.notes;
  if (!runs.problem.empty()) {
    row.status = "FAIL";
    row.notes.push_back(runs.problem);
  }
  SceneRun* engines[2] = {runs.manibench.get(), runs.mujoco.get()};
  const char* names[2] = {"manibench/Simbody", "MuJoCo"};

  for (SceneRun* engine : engines) {
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
  if (engines[0]->getEpisodes() > 0 || engines[1]->getEpisodes() > 0) {
    std::ostringstream note;
    note << "episodes checked: manibench " << engines[0]->getEpisodes() << ", MuJoCo "
         << engines[1]->getEpisodes();
    row.notes.push_back(note.str());
  }
  double worst = 0;
  const std::string comparison = compareEpisodeEnds(*engines[0], *engines[1], worst);
  if (!comparison.empty()) {
    const bool within = scene.compare_tolerance <= 0 || worst <= scene.compare_tolerance;
    char limit[64] = "";
    if (scene.compare_tolerance > 0)
      std::snprintf(limit, sizeof limit, " (limit %g)", scene.compare_tolerance);
    row.notes.push_back(comparison + limit);
    if (!within) row.status = "FAIL";
  }
  for (int e = 0; e < 2; ++e)
    if (const std::string seen = engines[e]->describeChecks(); !seen.empty())
      row.notes.push_back(std::string(names[e]) + ": " + seen);
  const std::string work = describeWork(*engines[0]);
  if (!work.empty()) row.notes.push_back(work);
  if (!options.reference.empty() && engines[0]->getEpisodes() > 0)
    row.notes.push_back(compareWithReference(scene, options, *engines[0]));
  return row;
}

void printTable(const std::vector<Row>& rows) {
  std::printf("\n%-15s %-28s %-20s %-20s %-15s %s\n", "scene", "Simbody integrator", "Simbody env/s",
              "MuJoCo env/s", "MuJoCo/Simbody", "sanity");
  for (const Row& row : rows)
    std::printf("%-15s %-28s %-20s %-20s %-15s %s\n", row.scene.c_str(), row.integrator.c_str(),
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
  const std::string base = options.write_models + "/" + scene.name;
  if (scene.make_documents) {
    for (const auto& [suffix, text] : scene.make_documents(options.run))
      if (!writeFile(base + suffix, text)) return false;
    return true;
  }
  MjcfOptions mjcf;
  mjcf.timestep = options.run.mujoco_dt;
  mjcf.integrator = options.run.mujoco_integrator.empty() ? scene.mujoco_integrator
                                                          : options.run.mujoco_integrator;
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
      std::printf("%-15s %s\n", scene.name.c_str(), scene.description.c_str());
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
              kTicksPerEnvStep, kControlDt * 1e3, mj_versionString(), options.run.mujoco_dt * 1e3);
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
