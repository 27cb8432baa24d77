// What an environment is built with: the options manibench/config.hpp
// derives from the layered YAML configuration, and their checks.
#pragma once

#include <manibench/observation.hpp>
#include <manibench/scene.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace manibench {

// A contact material for one link (or every link) of an articulation,
// set after the task has built its scene and before it is finalized.
struct BodyContactMaterial {
  std::string articulation;
  std::string link;  // empty: every link of the articulation
  ContactMaterial material;
  std::string source;  // where it was configured ("my.yaml:7: ..."), for errors
};

// Self-collision of one articulation, set like BodyContactMaterial.
struct SelfCollisionSetting {
  std::string articulation;
  bool enabled = false;
  std::string source;
};

struct EnvironmentOptions {
  std::string task_config;        // YAML for the task plugin
  std::string controller;         // empty: the task's default controller
  std::string controller_config;  // empty: the task's controller config
  PhysicsSettings physics;
  // Applied in order, so a later entry for the same link wins.
  std::vector<BodyContactMaterial> contact_materials;
  std::optional<ContactMaterial> ground_material;  // unset: physics.default_material
  std::vector<SelfCollisionSetting> self_collision;
  // End the episode as soon as `success` holds (as ManiSkill's done flag).
  bool stop_on_success = true;
  // Overrides of the task's timing; unset: the task's own values. They
  // change getTaskDescription() too, so that everything downstream (the
  // controller's filter, policies, printing) sees the values in force.
  std::optional<double> control_frequency;    // Hz, > 0
  std::optional<uint32_t> frame_skip;         // >= 1
  std::optional<uint32_t> max_episode_steps;  // >= 1
  // The observation mode, cameras, lights and point-cloud sampling.
  ObservationOptions observation;
};

// Throws InvalidArgument for options no task could honour (timing
// overrides out of range, and validateObservationOptions' cases).
void validateEnvironmentOptions(const EnvironmentOptions& options);

}  // namespace manibench
