#include "bench_scenes.hpp"

#include "cabinet_twin.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace manibench::bench {
namespace {

// Central principal inertia of a solid box with these half extents.
Eigen::Vector3d boxInertia(double mass, const Eigen::Vector3d& h) {
  return mass / 3 *
         Eigen::Vector3d(h.y() * h.y() + h.z() * h.z(), h.x() * h.x() + h.z() * h.z(),
                         h.x() * h.x() + h.y() * h.y());
}

std::string format(const char* fmt, double a, double b = 0, double c = 0) {
  char buffer[256];
  std::snprintf(buffer, sizeof buffer, fmt, a, b, c);
  return buffer;
}

// --- 10-DoF arm holding still -------------------------------------------------

constexpr int kArmDof = 10;

BenchScene makeArm() {
  BenchScene scene;
  scene.name = "arm10";
  scene.description =
      "10-DoF revolute arm (1 kg links, 12 cm), velocity drives (damping 100, target 0) "
      "+ gravity/Coriolis balancing, holding a bent pose";
  scene.integrator = "implicit_euler";  // manibench's default
  scene.mujoco_integrator = "implicit";
  Model& model = scene.model;
  model.name = "arm10";
  Articulation arm;
  arm.name = "arm";
  arm.fixed_base = true;
  Link base;
  base.name = "base";
  base.mass = 5;
  base.inertia = Eigen::Vector3d::Constant(0.05);
  arm.links.push_back(base);
  const double length = 0.12, radius = 0.03, mass = 1.0;
  const double initial[kArmDof] = {0.3, 0.6, -0.5, 0.4, 0.7, -0.6, 0.2, 0.5, -0.4, 0.1};
  for (int i = 1; i <= kArmDof; ++i) {
    Link link;
    link.name = "link" + std::to_string(i);
    link.parent = i - 1;
    link.joint = Link::Joint::Revolute;
    link.joint_name = "joint" + std::to_string(i);
    link.origin = Eigen::Vector3d(0, 0, i == 1 ? 0.1 : length);
    // z, y, y, z, y, y, ...: twists and pitches, so gravity loads most joints.
    link.axis = i % 3 == 1 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitY();
    link.effort = 200;
    link.mass = mass;
    link.com = Eigen::Vector3d(0, 0, length / 2);
    // A solid rod of radius 3 cm along z.
    const double side = mass * (3 * radius * radius + length * length) / 12;
    link.inertia = Eigen::Vector3d(side, side, mass * radius * radius / 2);
    arm.links.push_back(link);
    model.initial_joints.push_back({0, link.joint_name, initial[i - 1]});
    model.drives.push_back({0, link.joint_name, 0.0, 100.0, true});
  }
  model.articulations.push_back(arm);

  scene.policy = [](long, long, std::vector<DriveTarget>& targets) {
    for (DriveTarget& target : targets) target = DriveTarget{0, 0};  // velocity 0
  };
  std::vector<double> q0(initial, initial + kArmDof);
  scene.check = [q0](const Engine& engine) -> std::string {
    double drift = 0;
    for (int i = 0; i < kArmDof; ++i)
      drift = std::max(drift, std::abs(engine.getJointPosition(0, "joint" + std::to_string(i + 1)) - q0[i]));
    if (drift > 1e-3) return format("the arm drifted %.3g rad from its pose (limit 1 mrad)", drift);
    return {};
  };
  return scene;
}

// --- drawer on a slider, gripper pulling its handle -----------------------------

constexpr double kCloseTime = 0.2, kPullStart = 0.6, kPullEnd = 2.1;  // s
constexpr double kPullSpeed = 0.15;                                  // m/s
constexpr double kFingerOpen = 0.03, kFingerClosed = -0.01;          // m

BenchScene makeDrawer() {
  BenchScene scene;
  scene.name = "drawer";
  scene.description =
      "fixed cabinet, 2 kg drawer on a slider (damping 5), box handle; a carriage with two "
      "box fingers (position drives 1000/100) squeezes the handle (20 N) and pulls at 15 cm/s";
  scene.integrator = "implicit_euler";  // manibench's default
  scene.mujoco_integrator = "implicit";
  scene.needs_box_box = true;
  scene.episode_ticks = 250;  // 2.5 s: open, close, pull 22.5 cm, hold
  scene.settle_time = 0;
  Model& model = scene.model;
  model.name = "drawer";
  model.friction = 1.0;  // grasp friction (0.5 is marginal, Simbody notes)

  Articulation cabinet;
  cabinet.name = "cabinet";
  cabinet.fixed_base = true;
  Link body;
  body.name = "body";
  body.mass = 20;
  body.inertia = boxInertia(20, Eigen::Vector3d(0.2, 0.3, 0.3));
  body.com = Eigen::Vector3d(-0.21, 0, 0.3);
  body.shapes.push_back(Shape::box(Eigen::Vector3d(0.2, 0.3, 0.3), Eigen::Vector3d(-0.21, 0, 0.3)));
  cabinet.links.push_back(body);
  Link drawer;
  drawer.name = "drawer";
  drawer.parent = 0;
  drawer.joint = Link::Joint::Prismatic;
  drawer.joint_name = "slide";
  drawer.origin = Eigen::Vector3d(0, 0, 0.45);
  drawer.axis = Eigen::Vector3d::UnitX();
  drawer.limited = true;
  drawer.lower = 0;
  drawer.upper = 0.35;
  drawer.damping = 5;
  drawer.mass = 2;
  drawer.com = Eigen::Vector3d(-0.19, 0, 0);
  drawer.inertia = boxInertia(2, Eigen::Vector3d(0.19, 0.25, 0.08));
  drawer.shapes.push_back(Shape::box(Eigen::Vector3d(0.01, 0.25, 0.08), Eigen::Vector3d(-0.01, 0, 0)));
  // The handle bar: 2 x 12 x 2 cm, 4 cm in front of the drawer's face.
  drawer.shapes.push_back(Shape::box(Eigen::Vector3d(0.01, 0.06, 0.01), Eigen::Vector3d(0.05, 0, 0)));
  cabinet.links.push_back(drawer);
  model.articulations.push_back(cabinet);

  // The gripper's mount sits at the handle's centre; the carriage slides
  // along x, the fingers along +z and -z (q = half the opening).
  Articulation gripper;
  gripper.name = "gripper";
  gripper.fixed_base = true;
  gripper.root_position = Eigen::Vector3d(0.05, 0, 0.45);
  Link mount;
  mount.name = "mount";
  mount.mass = 1;
  mount.inertia = Eigen::Vector3d::Constant(0.01);
  gripper.links.push_back(mount);
  Link carriage;
  carriage.name = "carriage";
  carriage.parent = 0;
  carriage.joint = Link::Joint::Prismatic;
  carriage.joint_name = "pull";
  carriage.axis = Eigen::Vector3d::UnitX();
  carriage.effort = 500;
  carriage.mass = 2;
  carriage.inertia = boxInertia(2, Eigen::Vector3d(0.05, 0.05, 0.05));
  gripper.links.push_back(carriage);
  const Eigen::Vector3d pad(0.01, 0.01, 0.005);
  for (int side : {+1, -1}) {
    Link finger;
    finger.name = side > 0 ? "finger_top" : "finger_bottom";
    finger.parent = 1;
    finger.joint = Link::Joint::Prismatic;
    finger.joint_name = side > 0 ? "top" : "bottom";
    finger.axis = Eigen::Vector3d(0, 0, side);
    finger.limited = true;
    finger.lower = -0.02;
    finger.upper = 0.05;
    finger.effort = 100;
    finger.mass = 0.05;
    // The frame is on the pad's inner face; the pad extends outwards.
    finger.com = Eigen::Vector3d(0, 0, side * pad.z());
    finger.inertia = boxInertia(finger.mass, pad);
    finger.shapes.push_back(Shape::box(pad, finger.com));
    gripper.links.push_back(finger);
    model.initial_joints.push_back({1, finger.joint_name, kFingerOpen});
  }
  model.articulations.push_back(gripper);
  // drives[0]: carriage velocity; [1], [2]: finger positions.
  model.drives.push_back({1, "pull", 0, 1000, true});
  model.drives.push_back({1, "top", 1000, 100, true});
  model.drives.push_back({1, "bottom", 1000, 100, true});

  scene.policy = [](long, long tick, std::vector<DriveTarget>& targets) {
    const double t = tick * kControlDt;
    const double finger = t < kCloseTime ? kFingerOpen : kFingerClosed;
    targets[0] = {0, t >= kPullStart && t < kPullEnd ? kPullSpeed : 0.0};
    targets[1] = {finger, 0};
    targets[2] = {finger, 0};
  };
  scene.check = [](const Engine& engine) -> std::string {
    const double opened = engine.getJointPosition(0, "slide");
    const double pulled = engine.getJointPosition(1, "pull");
    const double expected = kPullSpeed * (kPullEnd - kPullStart);
    if (!(opened > 0.8 * expected) || !(std::abs(pulled - opened) < 0.01))
      return format("the drawer opened %.3f m (expected %.3f m) while the gripper moved %.3f m",
                    opened, expected, pulled);
    return {};
  };
  return scene;
}

// --- the same under random commands (a learning agent's exploration) -----------

// "" if every listed joint is finite, within [lower - tolerance, upper +
// tolerance] and slower than `max_speed`.
struct JointBounds {
  int articulation;
  std::string joint;
  double lower, upper, max_speed;
};
std::string checkBounds(const Engine& engine, const std::vector<JointBounds>& bounds,
                        double tolerance) {
  for (const JointBounds& b : bounds) {
    const double q = engine.getJointPosition(b.articulation, b.joint);
    const double v = engine.getJointVelocity(b.articulation, b.joint);
    if (!(q >= b.lower - tolerance && q <= b.upper + tolerance))
      return "joint '" + b.joint + "' at " + format("%.4g, outside [%.4g, %.4g]", q, b.lower, b.upper) +
             format(" + %g", tolerance);
    if (!(std::abs(v) <= b.max_speed))
      return "joint '" + b.joint + "' moves at " + format("%.4g (limit %.4g)", v, b.max_speed);
  }
  return {};
}

constexpr double kArmRandomSpeed = 1.5;  // rad/s: targets in [-1.5, 1.5]
constexpr double kCarriageRandomSpeed = 0.3;  // m/s

// arm10 with a new random velocity target per joint every control tick, in
// 2 s episodes from the bent pose. No contact: both engines integrate the
// same equations, so their end states are compared too.
BenchScene makeArmRandom() {
  BenchScene scene = makeArm();
  scene.name = "arm10_random";
  scene.description =
      "arm10 under random velocity targets (uniform in +-1.5 rad/s, new every 10 ms tick), "
      "2 s episodes from the bent pose";
  scene.episode_ticks = 200;
  scene.settle_time = 0;
  scene.policy = [](long episode, long tick, std::vector<DriveTarget>& targets) {
    for (std::size_t i = 0; i < targets.size(); ++i)
      targets[i] = {0, uniformAt(-kArmRandomSpeed, kArmRandomSpeed, 0, episode, tick, int(i))};
  };
  std::vector<JointBounds> bounds;
  for (const Drive& drive : scene.model.drives) {
    bounds.push_back({0, drive.joint, -1e9, 1e9, 4 * kArmRandomSpeed});
    scene.compared_joints.emplace_back(0, drive.joint);
  }
  // Measured: 2 s of random commands end 0.005-0.006 rad apart (CPodes'
  // accuracy 1e-2, MuJoCo's 2 ms step).
  scene.compare_tolerance = 0.02;
  scene.check = [bounds](const Engine& engine) { return checkBounds(engine, bounds, 0); };
  return scene;
}

// drawer with random commands every control tick: the carriage a velocity
// in +-0.3 m/s, each finger a position between closed (squeezing the
// handle) and open. The fingers grab, slip and let go of the handle; the
// drawer is pushed and pulled only through that contact.
BenchScene makeDrawerRandom() {
  BenchScene scene = makeDrawer();
  scene.name = "drawer_random";
  scene.description =
      "drawer under random commands every 10 ms tick: carriage velocity in +-0.3 m/s, each "
      "finger a position between closed (squeezing the handle) and open; 2.5 s episodes";
  scene.policy = [](long episode, long tick, std::vector<DriveTarget>& targets) {
    targets[0] = {0, uniformAt(-kCarriageRandomSpeed, kCarriageRandomSpeed, 0, episode, tick, 0)};
    for (int i : {1, 2}) targets[i] = {uniformAt(kFingerClosed, kFingerOpen, 0, episode, tick, i), 0};
  };
  // Limits (+ 6 mm for the penalty stops and soft constraints: the
  // carriage's drive, up to 500 N, can push the drawer into its stop, and
  // manibench's stop gives 5 mm under it, 1e5 N/m); the carriage has none,
  // but a sane one stays near the handle.
  const std::vector<JointBounds> bounds = {
      {0, "slide", 0, 0.35, 2.0},
      {1, "pull", -0.5, 0.5, 2.0},
      {1, "top", -0.02, 0.05, 5.0},
      {1, "bottom", -0.02, 0.05, 5.0},
  };
  scene.check = [bounds](const Engine& engine) { return checkBounds(engine, bounds, 6e-3); };
  for (const JointBounds& b : bounds) scene.compared_joints.emplace_back(b.articulation, b.joint);
  scene.compare_tolerance = 0;  // contact: reported only
  return scene;
}

// --- free boxes / spheres resting on the floor ------------------------------------

// `count` bodies in columns of `stack` (1: all on the floor; more: boxes
// resting on boxes too), the columns 25 cm apart on a square grid.
BenchScene makeResting(bool boxes, int count, int stack = 1) {
  BenchScene scene;
  const std::string kind = boxes ? (stack > 1 ? "stacks" : "boxes") : "spheres";
  scene.name = kind + std::to_string(count);
  scene.description = std::to_string(count) + " free " +
                      (boxes ? "10 cm boxes" : "spheres of radius 5 cm") + " (1 kg) resting " +
                      (stack > 1 ? "in " + std::to_string(count / stack) + " stacks of " +
                                       std::to_string(stack) + " on the floor"
                                 : std::string("on the floor")) +
                      ", 25 cm apart";
  scene.needs_box_box = boxes && stack > 1;
  // manibench's default, which solves each contact island on its own and so
  // scales with the body count (CPodes' dense Newton iteration does not:
  // 100 bodies ran at 7-10 env/s). docs/performance.md compares them all.
  scene.integrator = "implicit_euler";
  scene.mujoco_integrator = "Euler";
  Model& model = scene.model;
  model.name = scene.name;
  model.ground = true;
  const double half = 0.05;
  const int columns = (count + stack - 1) / stack;
  const int side = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(columns))));
  for (int i = 0; i < count; ++i) {
    Articulation art;
    art.name = (boxes ? "box" : "sphere") + std::to_string(i);
    art.fixed_base = false;
    const int column = i / stack, level = i % stack;
    art.root_position = Eigen::Vector3d(0.25 * (column % side), 0.25 * (column / side),
                                        half * (1 + 2 * level));
    Link body;
    body.name = "body";
    body.mass = 1;
    if (boxes) {
      body.inertia = boxInertia(1, Eigen::Vector3d::Constant(half));
      body.shapes.push_back(Shape::box(Eigen::Vector3d::Constant(half)));
    } else {
      body.inertia = Eigen::Vector3d::Constant(0.4 * half * half);
      body.shapes.push_back(Shape::sphere(half));
    }
    art.links.push_back(body);
    model.articulations.push_back(art);
  }
  // Sane: the mean height within 5 mm of the resting height (half the size
  // on the floor), no body more than 1 cm off it, none slid or toppled more
  // than 1 cm sideways.
  std::vector<Eigen::Vector3d> start;
  for (const Articulation& art : model.articulations) start.push_back(art.root_position);
  scene.check = [start](const Engine& engine) -> std::string {
    double mean = 0, worst = 0, slid = 0;
    for (std::size_t i = 0; i < start.size(); ++i) {
      const Eigen::Vector3d p = engine.getRootPosition(static_cast<int>(i));
      const double error = p.z() - start[i].z();
      mean += error / start.size();
      worst = std::max(worst, std::abs(error));
      slid = std::max(slid, (p - start[i]).head<2>().norm());
    }
    if (!(std::abs(mean) <= 5e-3) || !(worst <= 1e-2) || !(slid <= 1e-2))
      return format("mean height %.4f m off the resting height (limit 5 mm), worst body %.4f m off, "
                    "largest horizontal drift %.4f m",
                    mean, worst, slid);
    return {};
  };
  return scene;
}

}  // namespace

std::vector<BenchScene> makeScenes() {
  std::vector<BenchScene> scenes;
  scenes.push_back(makeArm());
  scenes.push_back(makeDrawer());
  scenes.push_back(makeArmRandom());
  scenes.push_back(makeDrawerRandom());
  for (int n : {10, 100}) scenes.push_back(makeResting(true, n));
  for (int n : {10, 100}) scenes.push_back(makeResting(false, n));
  // Not in the list: the box pile with box-box contact as well.
  scenes.push_back(makeResting(true, 100, 4));
  scenes.push_back(makeCabinetTwinScene());
  return scenes;
}

}  // namespace manibench::bench
