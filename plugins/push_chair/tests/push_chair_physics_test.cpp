// Physical validation of the generated chairs (supplement B.8), in the
// real scene (Simbody, our contact, the default implicit_euler integrator)
// with the task's materials: the chair alone stays put and upright; its
// casters carry its weight; pushed at the seat by a paddle it rolls, its
// casters swivel to trail the motion and it coasts to a stop; pushed hard
// at the top of the backrest it tips over.
#include <gtest/gtest.h>

#include <manibench/scene.hpp>

#include <cmath>
#include <cstdlib>
#include <iostream>
#include <optional>

#include "push_chair.hpp"

namespace {

namespace pc = push_chair;
using manibench::DriveCommand;
using manibench::Pose;
using manibench::Scene;

const bool kVerbose = std::getenv("PUSH_CHAIR_VERBOSE") != nullptr;

// A paddle on a horizontal rail (a prismatic joint along world +x), driven
// at a set speed by a stiff velocity drive: a pusher of any strength.
std::string makePusherUrdf(double width, double height) {
  return "<?xml version=\"1.0\"?><robot name=\"pusher\"><link name=\"rail\"/>"
         "<link name=\"paddle\"><inertial><mass value=\"5\"/><inertia ixx=\"0.1\" ixy=\"0\" ixz=\"0\" iyy=\"0.1\" "
         "iyz=\"0\" izz=\"0.1\"/></inertial><collision><geometry><box size=\"0.04 " +
         std::to_string(width) + " " + std::to_string(height) +
         "\"/></geometry></collision></link>"
         "<joint name=\"push\" type=\"prismatic\"><parent link=\"rail\"/><child link=\"paddle\"/>"
         "<axis xyz=\"1 0 0\"/><limit lower=\"-10\" upper=\"10\" effort=\"20000\" velocity=\"10\"/></joint></robot>";
}

struct ChairScene {
  std::unique_ptr<Scene> scene;
  pc::ChairModel model;
  int chair = -1, pusher = -1, root = -1;
  std::vector<int> wheels, casters;  // links
  std::vector<int> swivel_joints;

  Pose root_pose() const { return scene->getLinkPose(root); }
  double tilt() const {
    return std::acos(std::clamp((root_pose().orientation * Eigen::Vector3d::UnitZ()).z(), -1.0, 1.0));
  }
  void drivePusher(double speed) {
    DriveCommand c{};
    c.damping = 20000;
    c.velocity_target = speed;
    scene->setDriveCommands(pusher, {0}, {c});
  }
};

// The chair at the origin facing +x (seat front), every joint at rest and
// the casters at `caster_angle` (NaN: each its own), joint friction and
// damping at the middle of the task's ranges (seat 0.1 N m, 10 N m s; the
// rest 0.05 N m and 0.25, the casters' damping as N s/m at their lever, as
// the task's reset does); optionally a pusher whose paddle centre is
// at `pusher_at`.
ChairScene makeChairScene(const std::string& id, std::optional<Eigen::Vector3d> pusher_at = std::nullopt,
                          double caster_angle = NAN) {
  ChairScene s;
  s.model = pc::generateChair(id);
  manibench::PhysicsSettings settings;
  settings.default_density = 200;
  s.scene = std::make_unique<Scene>(settings);
  Scene& scene = *s.scene;
  scene.addGround(0);
  s.chair = scene.addUrdfString(s.model.urdf, "", "chair", Pose(), false);
  if (pusher_at) {
    Pose p;
    p.position = *pusher_at;
    s.pusher = scene.addUrdfString(makePusherUrdf(0.3, 0.06), "", "pusher", p, true);
  }
  manibench::ContactMaterial ground, chair, wheel;
  ground.static_friction = ground.dynamic_friction = 0.5;
  chair.static_friction = chair.dynamic_friction = 0.1;
  wheel.static_friction = wheel.dynamic_friction = 1.0;
  scene.setGroundMaterial(ground);
  scene.setContactMaterial(s.chair, "", chair);
  for (const std::string& w : s.model.wheel_links) scene.setContactMaterial(s.chair, w, wheel);
  scene.finalize();
  s.root = scene.findLink(s.chair, "base");
  const auto& joints = scene.getJoints(s.chair);
  Eigen::VectorXd q = Eigen::VectorXd::Zero(Eigen::Index(joints.size()));
  for (std::size_t j = 0; j < joints.size(); ++j) {
    const std::string& name = joints[j].name;
    const bool seat = name == "seat_swivel";
    const bool wheel = name.rfind("caster_wheel", 0) == 0, swivel = name.rfind("caster_swivel", 0) == 0;
    // as the task's reset: caster damping as N s/m where the floor pushes (times lever^2)
    double damping = seat ? 10.0 : 0.25, friction = seat ? 0.1 : 0.05;
    for (const pc::ChairJoint& c : s.model.joints)
      if (c.name == name && (wheel || swivel)) damping *= c.lever * c.lever;
    scene.setJointDynamics(s.chair, int(j), damping, friction);
    if (name.rfind("caster_swivel_", 0) == 0) {
      s.swivel_joints.push_back(int(j));
      q[Eigen::Index(j)] = std::isnan(caster_angle) ? 2.4 * double(j) - 1.0 : caster_angle;
    }
  }
  scene.setJointPositions(s.chair, q);
  for (const std::string& w : s.model.wheel_links) {
    s.wheels.push_back(scene.findLink(s.chair, w));
    s.casters.push_back(scene.findLink(s.chair, "caster_" + w.substr(6)));
  }
  return s;
}

// How well the casters trail a motion along `direction` (horizontal): the
// worst over the casters of the cosine between (wheel - swivel axis) and
// -direction; 1 is perfect trailing.
double calcWorstTrailing(const ChairScene& s, const Eigen::Vector2d& direction) {
  double worst = 1;
  for (std::size_t k = 0; k < s.wheels.size(); ++k) {
    const Eigen::Vector2d swivel = s.scene->getLinkPose(s.casters[k]).position.head<2>();
    const Eigen::Vector2d wheel = s.scene->getLinkPose(s.wheels[k]).position.head<2>();
    worst = std::min(worst, (wheel - swivel).normalized().dot(-direction.normalized()));
  }
  return worst;
}

TEST(PushChairPhysics, ChairLeftAloneStaysPutAndUpright) {
  for (const std::string id : {"3000", "3007", "3104"}) {
    ChairScene s = makeChairScene(id);
    const Eigen::Vector3d start = s.root_pose().position;
    double most_tilt = 0, most_speed = 0;
    for (int tick = 0; tick < 1000; ++tick) {  // 10 s
      s.scene->advance(0.01);
      most_tilt = std::max(most_tilt, s.tilt());
      most_speed = std::max(most_speed, s.scene->getLinkTwist(s.root).linear.norm());
    }
    const double moved = (s.root_pose().position - start).norm();
    if (kVerbose)
      std::cout << id << ": moved " << moved * 1e3 << " mm, tilt " << most_tilt << " rad, speed " << most_speed
                << " m/s\n";
    EXPECT_LT(moved, 0.01) << id;
    EXPECT_LT(most_tilt, 0.01) << id;
  }
}

TEST(PushChairPhysics, CastersCarryTheChairsWeight) {
  for (const std::string id : {"3001", "3102"}) {
    ChairScene s = makeChairScene(id);
    for (int tick = 0; tick < 100; ++tick) s.scene->advance(0.01);
    // The chair's mass from its kinetic energy at 1 m/s (every body moving
    // with the root): independent of the generator's own sums.
    Eigen::Vector3d weight_carried = Eigen::Vector3d::Zero();
    for (const int w : s.wheels) weight_carried += s.scene->calcContactForce(w, -1);
    Eigen::Vector3d others = Eigen::Vector3d::Zero();
    for (const int link : {s.root, s.scene->findLink(s.chair, "seat")}) others += s.scene->calcContactForce(link, -1);
    const manibench::SceneState rest = s.scene->saveState();
    manibench::Twist twist;
    twist.linear = Eigen::Vector3d(1, 0, 0);
    s.scene->setJointVelocities(s.chair, Eigen::VectorXd::Zero(Eigen::Index(s.scene->getJoints(s.chair).size())));
    s.scene->setRootTwist(s.chair, twist);
    const double mass = 2 * s.scene->calcKineticEnergy();
    s.scene->restoreState(rest);
    if (kVerbose) std::cout << id << ": mass " << mass << " kg, wheels carry " << weight_carried.transpose() << " N\n";
    EXPECT_GT(mass, 3.0) << id;
    EXPECT_NEAR(weight_carried.z(), mass * 9.81, 0.01 * mass * 9.81) << id;
    EXPECT_LT(weight_carried.head<2>().norm(), 0.01 * mass * 9.81) << id;
    EXPECT_LT(others.norm(), 1e-9) << id << ": only the wheels touch the ground";
  }
}

TEST(PushChairPhysics, PushedAtTheSeatItRollsCastersTrailAndItCoastsToAStop) {
  for (const std::string id : {"3002", "3005", "3103"}) {
    const pc::ChairParams p = pc::getChairParams(id);
    const double height = p.seat_height - p.seat_thickness / 2;
    // Paddle 6 cm in front of the cushion's front face, pushing along -x;
    // casters all pointing along +x (they must swivel round to trail).
    ChairScene s = makeChairScene(id, Eigen::Vector3d(p.seat_offset + p.seat_depth / 2 + 0.08, 0, height), 0.0);
    const Eigen::Vector3d start = s.root_pose().position;
    double most_tilt = 0;
    s.drivePusher(-0.4);
    for (int tick = 0; tick < 150; ++tick) {  // 1.5 s at 0.4 m/s
      s.scene->advance(0.01);
      most_tilt = std::max(most_tilt, s.tilt());
    }
    const double trailing = calcWorstTrailing(s, Eigen::Vector2d(-1, 0));
    const double speed_at_release = s.scene->getLinkTwist(s.root).linear.norm();
    const Eigen::Vector3d at_release = s.root_pose().position;
    s.drivePusher(0.5);  // back away
    double stopped_after = -1;
    for (int tick = 0; tick < 500; ++tick) {
      s.scene->advance(0.01);
      most_tilt = std::max(most_tilt, s.tilt());
      if (stopped_after < 0 && s.scene->getLinkTwist(s.root).linear.norm() < 1e-3) stopped_after = 0.01 * (tick + 1);
    }
    const Eigen::Vector3d end = s.root_pose().position;
    if (kVerbose)
      std::cout << id << ": pushed " << (at_release - start).transpose() << " m, trailing " << trailing
                << ", speed at release " << speed_at_release << " m/s, coasted " << (end - at_release).norm()
                << " m, stopped after " << stopped_after << " s, tilt " << most_tilt << "\n";
    EXPECT_LT(at_release.x() - start.x(), -0.4) << id << ": rolls with the paddle";
    EXPECT_LT(std::abs(at_release.y() - start.y()), 0.1) << id;
    EXPECT_GT(trailing, 0.9) << id << ": every caster trails the motion";
    EXPECT_GT(speed_at_release, 0.3) << id;
    EXPECT_LT(end.x(), at_release.x() - 0.002) << id << ": coasts on after the paddle stops";
    EXPECT_GT(stopped_after, 0) << id << ": and stops";
    EXPECT_LT(most_tilt, 0.05 * M_PI) << id << ": upright all along";
  }
}

TEST(PushChairPhysics, PushedHardAtTheBackrestTopItTipsPushedGentlyItRolls) {
  for (const std::string id : {"3003", "3006", "3101"}) {
    const pc::ChairModel model = pc::generateChair(id);
    const pc::ChairParams p = pc::getChairParams(id);
    // From behind, along +x, 5 cm below the top of the backrest.
    const double rear = p.seat_offset - p.seat_depth / 2 - 0.03 - std::sin(p.backrest_angle) * p.backrest_height;
    // A shove: the paddle speeds up at 12 m/s^2 (to 6 m/s). Rolling freely,
    // the chair only stays up while F (H - h_com) < m g L, that is while
    // a < g L / (H - h_com), about 5 m/s^2 for these chairs. A gentle push
    // (1 m/s^2 to 0.3 m/s) at the same place rolls it upright.
    for (const double acceleration : {12.0, 1.0}) {
      ChairScene s = makeChairScene(id, Eigen::Vector3d(rear - 0.1, 0, model.height - 0.05));
      const double top_speed = acceleration > 5 ? 6.0 : 0.3;
      double most_tilt = 0;
      for (int tick = 0; tick < 200; ++tick) {
        s.drivePusher(std::min(top_speed, acceleration * 0.01 * tick));
        s.scene->advance(0.01);
        most_tilt = std::max(most_tilt, s.tilt());
      }
      const double moved = s.root_pose().position.x();
      if (kVerbose)
        std::cout << id << ": pushed at " << model.height - 0.05 << " m with " << acceleration << " m/s^2: tilt "
                  << most_tilt << ", moved " << moved << " m\n";
      if (acceleration > 5) {
        EXPECT_GT(most_tilt, 0.5 * M_PI) << id << ": falls over";
      } else {
        EXPECT_LT(most_tilt, 0.05 * M_PI) << id << ": stays upright";
        EXPECT_GT(moved, 0.3) << id << ": and rolls";
      }
    }
  }
}

}  // namespace
