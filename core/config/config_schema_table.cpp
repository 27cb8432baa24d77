// The configuration's schema: one table row per key (path, type, bounds,
// choices, description). Validation, nearest-key suggestions, list-item
// defaults (config_schema.cpp) and docs/configuration.md all follow it.
// Long because it is data: one row per key of the configuration.
#include <manibench/config.hpp>
#include <manibench/sdk/numbers.hpp>

#include <limits>
#include <string>
#include <vector>

namespace manibench {
namespace {

using sdk::kPi;

constexpr double kInf = std::numeric_limits<double>::infinity();

// Fluent construction of the table's rows.
struct Key {
  ConfigKey key;
  Key(std::string path, ConfigType type, std::string description) {
    key.path = std::move(path);
    key.type = type;
    key.description = std::move(description);
  }
  Key& in(double lower, double upper) {  // [lower, upper]
    return atLeast(lower).atMost(upper);
  }
  Key& atLeast(double lower) {
    key.lower = lower;
    key.lower_open = false;
    return *this;
  }
  Key& above(double lower) {
    key.lower = lower;
    key.lower_open = true;
    return *this;
  }
  Key& atMost(double upper) {
    key.upper = upper;
    key.upper_open = false;
    return *this;
  }
  Key& below(double upper) {
    key.upper = upper;
    key.upper_open = true;
    return *this;
  }
  Key& oneOf(std::vector<std::string> choices) {
    key.choices = std::move(choices);
    return *this;
  }
  Key& orNull() {
    key.nullable = true;
    return *this;
  }
  Key& required() {
    key.required = true;
    return *this;
  }
  Key& itemDefault(std::string yaml) {
    key.item_default = std::move(yaml);
    return *this;
  }
  operator ConfigKey() const { return key; }
};

using T = ConfigType;

// The contact material fields (Scene's ContactMaterial), shared by
// physics.contact.default, .ground and the per-body entries (where every
// field is optional: the default's value applies).
void addMaterialKeys(std::vector<ConfigKey>& keys, const std::string& prefix) {
  keys.push_back(Key(prefix + ".stiffness", T::Number,
                     "N/m per contact point, this surface alone (two surfaces combine in series)")
                     .above(0));
  keys.push_back(Key(prefix + ".dissipation", T::Number,
                     "Hunt-Crossley dissipation, s/m (0: perfectly elastic)")
                     .atLeast(0));
  keys.push_back(Key(prefix + ".static_friction", T::Number,
                     "static friction coefficient, at least dynamic_friction (surfaces combine "
                     "by geometric mean)")
                     .atLeast(0));
  keys.push_back(Key(prefix + ".dynamic_friction", T::Number, "dynamic friction coefficient")
                     .atLeast(0));
  keys.push_back(Key(prefix + ".viscous_friction", T::Number,
                     "s/m: the friction coefficient grows by this per m/s of slip speed")
                     .atLeast(0));
}

std::vector<ConfigKey> makeSchema() {
  std::vector<ConfigKey> k;
  // -- control and episode --------------------------------------------------
  k.push_back(Key("control", T::Map, "control timing and the controller"));
  k.push_back(Key("control.frequency", T::Number,
                  "control frequency, Hz: each control tick advances the physics 1/frequency s; "
                  "null: the task's")
                  .above(0)
                  .atMost(100000)
                  .orNull());
  k.push_back(Key("control.frame_skip", T::Int,
                  "control ticks per environment step; null: the task's")
                  .in(1, 100000)
                  .orNull());
  k.push_back(Key("control.controller", T::String,
                  "controller plugin by name (joint_velocity, joint_position, ...); null: the task's")
                  .orNull());
  k.push_back(Key("control.controller_config", T::FreeMap,
                  "the controller plugin's configuration, handed to it as YAML text; the "
                  "controller checks its own keys; null clears what lower layers set"));
  k.push_back(Key("episode", T::Map, "episode length"));
  k.push_back(Key("episode.max_steps", T::Int,
                  "environment steps before an episode times out; null: the task's")
                  .in(1, 1e9)
                  .orNull());

  // -- observation --------------------------------------------------------------
  k.push_back(Key("observation", T::Map, "what policies observe"));
  k.push_back(Key("observation.mode", T::Enum,
                  "state: the task's vector; pointcloud and rgbd add the cameras' points or "
                  "images (and render)")
                  .oneOf(getObservationModeNames()));
  k.push_back(Key("observation.rgb_dtype", T::Enum,
                  "rgbd's rgb: float32 in [0, 1] (ManiSkill's layout) or uint8 in [0, 255] (the "
                  "renderer's bytes: a quarter of the size, what image libraries expect; the "
                  "Python package's default)")
                  .oneOf(getRgbDtypeNames()));
  k.push_back(Key("observation.pointcloud", T::Map,
                  "subsampling of the fused point cloud (supplement D.1)"));
  k.push_back(Key("observation.pointcloud.per_mask", T::Int,
                  "points kept per segmentation mask first (all when fewer)")
                  .in(0, 1e7));
  k.push_back(Key("observation.pointcloud.masked_total", T::Int,
                  "masked points kept in all (all when fewer); at most total")
                  .in(0, 1e7));
  k.push_back(Key("observation.pointcloud.total", T::Int,
                  "points in all: background points above the ground fill up to it")
                  .in(1, 1e7));
  k.push_back(Key("observation.pointcloud.ground_height", T::Number,
                  "m; background points at or below it (the ground) are dropped"));
  k.push_back(Key("observation.pointcloud.pad", T::Bool,
                  "pad with zero points (origin, black, no mask) up to total, as ManiSkill-Learn"));

  // -- physics ----------------------------------------------------------------
  k.push_back(Key("physics", T::Map, "the Simbody scene's solver, gravity and contact"));
  k.push_back(Key("physics.gravity", T::Vector3, "gravity, m/s^2, world frame (z up)"));
  k.push_back(Key("physics.integrator", T::Enum,
                  "implicit_euler: fixed step physics.implicit_step, implicit in the stiff forces "
                  "(drives, joint damping and stops, contact): the same cost per step whatever "
                  "the actions; cpodes: implicit, error-controlled (cost grows with jerky "
                  "actions and with many free bodies); rk_merson: explicit Runge-Kutta-Merson, "
                  "error-controlled; semi_explicit_euler: fixed step physics.fixed_step, explicit")
                  .oneOf({"implicit_euler", "cpodes", "rk_merson", "semi_explicit_euler"}));
  k.push_back(Key("physics.implicit_step", T::Number, "step of implicit_euler, s")
                  .above(0)
                  .atMost(0.1));
  k.push_back(Key("physics.accuracy", T::Number,
                  "relative accuracy of cpodes and rk_merson; smaller is more precise and slower")
                  .above(0)
                  .atMost(1));
  k.push_back(Key("physics.fixed_step", T::Number, "step of semi_explicit_euler, s")
                  .above(0)
                  .atMost(0.1));
  k.push_back(Key("physics.friction_stiffness", T::Number,
                  "stiction spring per contact point, N/m: holds a contact up to static friction "
                  "(so a box on a slope does not creep)")
                  .above(0));
  k.push_back(Key("physics.friction_damping", T::Number,
                  "stiction damper per contact point, N s/m")
                  .atLeast(0));
  k.push_back(Key("physics.default_density", T::Number,
                  "kg/m^3; gives mass to links that have collision geometry but no <inertial>")
                  .above(0));
  k.push_back(Key("physics.divergence_speed_limit", T::Number,
                  "any joint speed above this (rad/s or m/s) stops the episode as diverged")
                  .above(0));
  k.push_back(Key("physics.default_joint_damping", T::Number,
                  "N m s/rad or N s/m; damping of joints whose URDF has no <dynamics>")
                  .atLeast(0));
  k.push_back(Key("physics.self_collision", T::Map,
                  "articulation name -> whether its links touch each other (default: no; links "
                  "joined by a joint never do)"));
  k.push_back(Key("physics.self_collision.*", T::Bool, "self-collision of that articulation"));
  k.push_back(Key("physics.contact", T::Map, "contact materials"));
  k.push_back(Key("physics.contact.default", T::Map,
                  "the material of every link not listed in bodies, and of the ground unless "
                  "ground says otherwise"));
  addMaterialKeys(k, "physics.contact.default");
  k.push_back(Key("physics.contact.ground", T::Map,
                  "the ground's material; fields left out take physics.contact.default's value"));
  addMaterialKeys(k, "physics.contact.ground");
  k.push_back(Key("physics.contact.bodies", T::List,
                  "per-link materials, applied in order (a later entry wins); fields left out "
                  "take physics.contact.default's value"));
  k.push_back(Key("physics.contact.bodies[].articulation", T::String,
                  "the articulation's name in the scene (as the task added it)")
                  .required());
  k.push_back(Key("physics.contact.bodies[].link", T::String,
                  "the link's name in its URDF; `NAME*`: every link whose name starts with NAME (none is not an "
                  "error); null: every link of the articulation")
                  .orNull()
                  .itemDefault("null"));
  addMaterialKeys(k, "physics.contact.bodies[]");

  // -- rendering (carried and checked; the renderer is a later issue) ----------
  k.push_back(Key("lights", T::Map, "scene lighting (for the renderer)"));
  k.push_back(Key("lights.ambient", T::Color, "ambient light, linear RGB").atLeast(0));
  k.push_back(Key("lights.directional", T::List, "directional lights (sun-like)"));
  k.push_back(Key("lights.directional[].direction", T::Vector3,
                  "direction the light travels, world frame (need not be unit length)")
                  .required());
  k.push_back(Key("lights.directional[].color", T::Color, "linear RGB intensity")
                  .atLeast(0)
                  .itemDefault("[1, 1, 1]"));
  k.push_back(Key("lights.directional[].shadow", T::Bool, "whether the light casts shadows")
                  .itemDefault("false"));
  k.push_back(Key("lights.point", T::List, "point lights"));
  k.push_back(Key("lights.point[].position", T::Vector3, "m, world frame").required());
  k.push_back(Key("lights.point[].color", T::Color, "linear RGB intensity")
                  .atLeast(0)
                  .itemDefault("[1, 1, 1]"));

  k.push_back(Key("cameras", T::List, "cameras (for the renderer and the observations)"));
  k.push_back(Key("cameras[].name", T::String, "unique camera name").required());
  k.push_back(Key("cameras[].articulation", T::String,
                  "articulation of the mount link; null: the camera is fixed in the world")
                  .orNull()
                  .itemDefault("null"));
  k.push_back(Key("cameras[].link", T::String,
                  "mount link (needs articulation); null: the articulation's root link")
                  .orNull()
                  .itemDefault("null"));
  k.push_back(Key("cameras[].pose", T::Map,
                  "pose in the mount frame; the camera looks along its +x axis, +z up")
                  .itemDefault("{position: [0, 0, 0], rpy: [0, 0, 0]}"));
  k.push_back(Key("cameras[].pose.position", T::Vector3, "m").itemDefault("[0, 0, 0]"));
  k.push_back(Key("cameras[].pose.rpy", T::Vector3,
                  "roll, pitch, yaw, rad (extrinsic x-y-z)")
                  .itemDefault("[0, 0, 0]"));
  k.push_back(Key("cameras[].width", T::Int, "image width, pixels").in(1, 16384).itemDefault("400"));
  k.push_back(Key("cameras[].height", T::Int, "image height, pixels").in(1, 16384).itemDefault("160"));
  k.push_back(Key("cameras[].fovy", T::Number, "vertical field of view, rad")
                  .above(0)
                  .below(kPi)
                  .itemDefault("1.0471975511965976"));
  k.push_back(Key("cameras[].near", T::Number, "near clipping distance, m (below far)")
                  .above(0)
                  .itemDefault("0.1"));
  k.push_back(Key("cameras[].far", T::Number, "far clipping distance, m").above(0).itemDefault("10"));

  k.push_back(Key("materials", T::Map,
                  "named visual materials (for the renderer); keys are material names"));
  k.push_back(Key("materials.*", T::Map, "one visual material"));
  k.push_back(Key("materials.*.color", T::Color, "base color, linear RGB or RGBA in [0, 1]")
                  .in(0, 1)
                  .itemDefault("[0.8, 0.8, 0.8, 1]"));
  k.push_back(Key("materials.*.roughness", T::Number, "0 (mirror) to 1 (matte)")
                  .in(0, 1)
                  .itemDefault("0.5"));
  k.push_back(Key("materials.*.metallic", T::Number, "0 (dielectric) to 1 (metal)")
                  .in(0, 1)
                  .itemDefault("0"));
  k.push_back(Key("materials.*.specular", T::Number, "specular reflectance, 0 to 1")
                  .in(0, 1)
                  .itemDefault("0.5"));

  // -- layouts (carried and checked; randomized placement is a later issue) -----
  k.push_back(Key("layouts", T::Map,
                  "randomized initial placements; keys name what is placed (robot, target, ...)"));
  k.push_back(Key("layouts.*", T::Map, "one placement, relative to the task's reference object"));
  k.push_back(Key("layouts.*.distance", T::Range, "[min, max] horizontal distance, m").atLeast(0));
  k.push_back(Key("layouts.*.heading", T::Range,
                  "[min, max] direction from the reference to the placed thing, rad")
                  .in(-2 * kPi, 2 * kPi));
  k.push_back(Key("layouts.*.yaw_noise", T::Number,
                  "half-width of the uniform noise added to the facing yaw, rad")
                  .in(0, kPi));
  k.push_back(Key("layouts.*.height", T::Range, "[min, max] height of the root, m"));

  // -- the task's own keys -------------------------------------------------------
  k.push_back(Key("task", T::FreeMap,
                  "the task plugin's configuration, handed to it as YAML text; the task checks "
                  "its own keys"));
  return k;
}

}  // namespace

const std::vector<ConfigKey>& getConfigSchema() {
  static const std::vector<ConfigKey> schema = makeSchema();
  return schema;
}

}  // namespace manibench
