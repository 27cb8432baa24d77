// The layers of the configuration, their merge, and the EnvironmentOptions
// a merged configuration asks for.
#include <manibench/config.hpp>
#include <manibench/task_name.hpp>

#include <cassert>
#include <charconv>
#include <cctype>

namespace manibench {
namespace {

// The lowest layer. It mirrors the defaults of PhysicsSettings and
// ObservationOptions (config tests hold them together; the directional
// lights are the exception they name) and names every key that is not
// inside a list item or a free-form map; docs/configuration.md explains each.
const char* const kBuiltinConfig = R"(# manibench built-in defaults (the lowest configuration layer)
control:
  frequency: null          # Hz; null: the task's
  frame_skip: null         # null: the task's
  controller: null         # null: the task's
  controller_config: {}
episode:
  max_steps: null          # null: the task's
physics:
  gravity: [0, 0, -9.81]
  integrator: implicit_euler
  implicit_step: 2.0e-3
  accuracy: 1.0e-2
  fixed_step: 5.0e-4
  friction_stiffness: 1.0e+5
  friction_damping: 20
  default_density: 1000
  divergence_speed_limit: 1000
  self_collision: {}
  contact:
    default:
      stiffness: 2.0e+5
      dissipation: 5.0
      static_friction: 0.8
      dynamic_friction: 0.6
      viscous_friction: 0.0
    ground: {}
    bodies: []
  default_joint_damping: 0
lights:
  ambient: [0.3, 0.3, 0.3]
  directional:
    - direction: [0, 1, -1]
      color: [1, 1, 1]
      shadow: true
  point: []
cameras: []
materials: {}
layouts: {}
task: {}
observation:
  mode: state
  rgb_dtype: float32
  pointcloud:
    per_mask: 50
    masked_total: 800
    total: 1200
    ground_height: 1.0e-3
    pad: true
)";

// Shortest text that reads back as exactly `value`.
std::string formatDouble(double value) {
  char buffer[64];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof(buffer), value);
  assert(ec == std::errc());
  return std::string(buffer, end);
}

ConfigNode makeScalar(const std::string& text, const ConfigOrigin& origin) {
  ConfigNode node;
  node.kind = ConfigNode::Kind::Scalar;
  node.scalar = text;
  node.origin = origin;
  return node;
}

ConfigNode makeMap(const ConfigOrigin& origin) {
  ConfigNode node;
  node.kind = ConfigNode::Kind::Map;
  node.origin = origin;
  return node;
}

void setOrigin(ConfigNode& node, const ConfigOrigin& origin) {
  node.origin = origin;
  for (ConfigNode& item : node.items) setOrigin(item, origin);
  for (ConfigEntry& e : node.entries) {
    e.key_origin = origin;
    setOrigin(e.value, origin);
  }
}

// Whether every value in `node` comes from `layer` (an empty map or list
// counts by its own origin).
bool isOnlyFrom(const ConfigNode& node, ConfigLayer layer) {
  if (node.isMap() && !node.entries.empty()) {
    for (const ConfigEntry& e : node.entries)
      if (!isOnlyFrom(e.value, layer)) return false;
    return true;
  }
  return node.origin.layer == layer;
}

// The value at `path`, which the built-in layer and validation guarantee
// in a configuration from calcConfig.
const ConfigNode& getPath(const ConfigNode& config, const std::string& path) {
  const ConfigNode* node = config.findPath(path);
  assert(node != nullptr && "calcEnvironmentOptions needs a configuration from calcConfig");
  return *node;
}

double getNumber(const ConfigNode& config, const std::string& path) {
  const std::optional<double> value = calcNumber(getPath(config, path));
  assert(value && "a number key holds no number: the configuration was not validated");
  return *value;
}

// A timing value the user (not the task description) set; nullopt otherwise.
const ConfigNode* findUserValue(const ConfigNode& config, const std::string& path) {
  const ConfigNode* node = config.findPath(path);
  if (node == nullptr || node->isNull() || isOnlyFrom(*node, ConfigLayer::TaskDescription))
    return nullptr;
  return node;
}

// A material: the fields `node` sets, the others from `fallback`.
ContactMaterial calcMaterial(const ConfigNode& node, const ContactMaterial& fallback) {
  ContactMaterial material = fallback;
  auto read = [&](const char* key, double& field) {
    if (const ConfigNode* value = node.find(key)) field = *calcNumber(*value);
  };
  read("stiffness", material.stiffness);
  read("dissipation", material.dissipation);
  read("static_friction", material.static_friction);
  read("dynamic_friction", material.dynamic_friction);
  read("viscous_friction", material.viscous_friction);
  return material;
}

Eigen::Vector3d calcVector3(const ConfigNode& node) {
  assert(node.items.size() >= 3);
  return Eigen::Vector3d(*calcNumber(node.items[0]), *calcNumber(node.items[1]),
                         *calcNumber(node.items[2]));
}

// The entries of a light list (none when `path` is absent): `start` reads
// what is the kind's own (a direction and shadow, a position), then the
// color. The schema has checked every entry already.
template <class Light, class Start>
std::vector<Light> calcLights(const ConfigNode& config, const char* path, Start start) {
  std::vector<Light> lights;
  if (const ConfigNode* list = config.findPath(path))
    for (const ConfigNode& item : list->items) {
      Light light = start(item);
      light.color = calcVector3(*item.find("color")).cast<float>();
      lights.push_back(light);
    }
  return lights;
}

// Cameras and lights, for the renderer of the visual observation modes.
void calcRenderOptions(const ConfigNode& config, ObservationOptions& options) {
  LightingSpec& lighting = options.lighting;
  lighting.ambient = calcVector3(getPath(config, "lights.ambient")).cast<float>();
  lighting.directional = calcLights<DirectionalLight>(config, "lights.directional", [](const ConfigNode& item) {
    DirectionalLight light;
    light.direction = calcVector3(*item.find("direction")).cast<float>();
    light.shadow = *calcBool(*item.find("shadow"));
    return light;
  });
  lighting.point = calcLights<PointLight>(config, "lights.point", [](const ConfigNode& item) {
    PointLight light;
    light.position = calcVector3(*item.find("position")).cast<float>();
    return light;
  });
  for (const char* kind : {"directional", "point"}) {
    const ConfigNode* list = config.findPath(std::string("lights.") + kind);
    if (list != nullptr && list->items.size() > std::size_t(LightingSpec::kMaxLights))
      throw ConfigError(list->origin.describe() + ": lights." + kind + ": at most " +
                        std::to_string(LightingSpec::kMaxLights) + " lights, got " +
                        std::to_string(list->items.size()));
  }

  for (const ConfigNode& item : getPath(config, "cameras").items) {
    CameraMount camera;
    camera.spec.name = item.find("name")->scalar;
    if (const ConfigNode* a = item.find("articulation"); a != nullptr && !a->isNull())
      camera.articulation = a->scalar;
    if (const ConfigNode* l = item.find("link"); l != nullptr && !l->isNull())
      camera.link = l->scalar;
    const ConfigNode& pose = *item.find("pose");
    const ConfigNode* position = pose.find("position");
    const ConfigNode* rpy = pose.find("rpy");
    if (position) camera.pose.position = calcVector3(*position);
    if (rpy) {
      // Extrinsic x-y-z (URDF rpy): R = Rz(yaw) Ry(pitch) Rx(roll).
      const Eigen::Vector3d a = calcVector3(*rpy);
      camera.pose.orientation = Eigen::AngleAxisd(a.z(), Eigen::Vector3d::UnitZ()) *
                                Eigen::AngleAxisd(a.y(), Eigen::Vector3d::UnitY()) *
                                Eigen::AngleAxisd(a.x(), Eigen::Vector3d::UnitX());
    }
    camera.spec.width = int(*calcInt(*item.find("width")));
    camera.spec.height = int(*calcInt(*item.find("height")));
    camera.spec.fovy = *calcNumber(*item.find("fovy"));
    camera.spec.near = *calcNumber(*item.find("near"));
    camera.spec.far = *calcNumber(*item.find("far"));
    camera.source = item.origin.describe() + ": cameras";
    options.cameras.push_back(std::move(camera));
  }
}

bool isWordCharacter(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

// Whether `word` occurs in `text` with no word character on either side.
bool containsWord(const std::string& text, const std::string& word) {
  for (std::size_t at = text.find(word); at != std::string::npos; at = text.find(word, at + 1)) {
    const bool starts = at == 0 || !isWordCharacter(text[at - 1]);
    const std::size_t end = at + word.size();
    const bool ends = end == text.size() || !isWordCharacter(text[end]);
    if (starts && ends) return true;
  }
  return false;
}

}  // namespace

const std::string& getBuiltinConfigText() {
  static const std::string text = kBuiltinConfig;
  return text;
}

ConfigNode calcBuiltinConfig() {
  return parseConfig(getBuiltinConfigText(), "built-in defaults", ConfigLayer::Builtin);
}

ConfigNode makeTaskConfigLayer(const TaskDescription& task) {
  const ConfigOrigin described{ConfigLayer::TaskDescription, "task " + task.name + " description", 0};
  ConfigNode layer = makeMap(described);
  ConfigNode& control = layer.updEntry("control", described);
  control = makeMap(described);
  control.updEntry("frequency", described) = makeScalar(formatDouble(task.control_frequency), described);
  control.updEntry("frame_skip", described) = makeScalar(std::to_string(task.frame_skip), described);
  if (!task.default_controller.empty())
    control.updEntry("controller", described) = makeScalar(task.default_controller, described);
  // The task's controller configuration is YAML text; as a layer it is a map.
  ConfigNode controller_config =
      parseConfig(task.controller_config, described.source + ", controller_config",
                  ConfigLayer::TaskDescription);
  if (controller_config.isNull()) controller_config = makeMap(described);
  if (!controller_config.isMap())
    throw ConfigError(controller_config.origin.describe() +
                      ": control.controller_config: the task's controller configuration must be a "
                      "map of keys");
  setOrigin(controller_config, described);
  control.updEntry("controller_config", described) = std::move(controller_config);
  ConfigNode& episode = layer.updEntry("episode", described);
  episode = makeMap(described);
  episode.updEntry("max_steps", described) = makeScalar(std::to_string(task.max_episode_steps), described);
  validateConfig(layer);

  ConfigNode defaults = parseConfig(task.default_config, "task " + task.name + " defaults", ConfigLayer::Task);
  validateConfig(defaults);
  if (defaults.isMap()) mergeConfig(layer, defaults);
  return layer;
}

ConfigNode calcConfig(const TaskDescription* task, const ConfigSources& sources) {
  ConfigNode config = calcBuiltinConfig();
  std::vector<ConfigNode> layers;
  if (task != nullptr) layers.push_back(makeTaskConfigLayer(*task));
  for (const std::string& file : sources.files) layers.push_back(loadConfigFile(file));
  for (const std::string& assignment : sources.overrides)
    layers.push_back(parseConfigOverride(assignment));
  for (const ConfigNode& layer : layers) {
    // Each layer on its own first, so that its errors name it.
    validateConfig(layer);
    if (!layer.isNull()) mergeConfig(config, layer);
  }
  completeConfig(config);
  validateConfig(config);
  return config;
}

ConfigNode loadTaskConfig(const PluginRegistry& registry, const std::string& task_name,
                          const ConfigSources& sources) {
  // A first instance, with no configuration, only to read the description
  // (its default_config layer among it). A fixed-object id configures as
  // its task.
  TaskDescription description;
  {
    TaskInstance probe(registry, resolveTaskId(registry, task_name).task, "");
    description = probe.getDescription();
  }
  return calcConfig(&description, sources);
}

EnvironmentOptions calcEnvironmentOptions(const ConfigNode& config) {
  EnvironmentOptions options;

  // -- physics -----------------------------------------------------------------
  PhysicsSettings& physics = options.physics;
  const ConfigNode& gravity = getPath(config, "physics.gravity");
  assert(gravity.items.size() == 3);
  const double gx = *calcNumber(gravity.items[0]);
  const double gy = *calcNumber(gravity.items[1]);
  // The scene's gravity is vertical (PhysicsSettings::gravity_z).
  if (gx != 0 || gy != 0)
    throw ConfigError(gravity.origin.describe() +
                      ": physics.gravity: the scene supports vertical gravity only; x and y must "
                      "be 0, got [" +
                      gravity.items[0].scalar + ", " + gravity.items[1].scalar + ", " +
                      gravity.items[2].scalar + "]");
  physics.gravity_z = *calcNumber(gravity.items[2]);
  physics.integrator = parseIntegrator(getPath(config, "physics.integrator").scalar);
  physics.implicit_step = getNumber(config, "physics.implicit_step");
  physics.accuracy = getNumber(config, "physics.accuracy");
  physics.fixed_step = getNumber(config, "physics.fixed_step");
  physics.friction_stiffness = getNumber(config, "physics.friction_stiffness");
  physics.friction_damping = getNumber(config, "physics.friction_damping");
  physics.default_density = getNumber(config, "physics.default_density");
  physics.divergence_speed_limit = getNumber(config, "physics.divergence_speed_limit");
  physics.default_joint_damping = getNumber(config, "physics.default_joint_damping");
  const ConfigNode& default_material = getPath(config, "physics.contact.default");
  physics.default_material = calcMaterial(default_material, ContactMaterial{});
  // The ground: the default material unless a field says otherwise.
  const ConfigNode& ground = getPath(config, "physics.contact.ground");
  if (!ground.entries.empty())
    options.ground_material = calcMaterial(ground, physics.default_material);
  for (const ConfigNode& body : getPath(config, "physics.contact.bodies").items) {
    BodyContactMaterial entry;
    entry.articulation = body.find("articulation")->scalar;
    const ConfigNode* link = body.find("link");
    if (link != nullptr && !link->isNull()) entry.link = link->scalar;
    entry.material = calcMaterial(body, physics.default_material);
    entry.source = body.origin.describe() + ": physics.contact.bodies";
    options.contact_materials.push_back(std::move(entry));
  }
  for (const ConfigEntry& e : getPath(config, "physics.self_collision").entries)
    options.self_collision.push_back(
        {e.key, *calcBool(e.value), e.value.origin.describe() + ": physics.self_collision." + e.key});

  // -- control and episode ----------------------------------------------------
  if (const ConfigNode* node = findUserValue(config, "control.frequency"))
    options.control_frequency = *calcNumber(*node);
  if (const ConfigNode* node = findUserValue(config, "control.frame_skip"))
    options.frame_skip = static_cast<uint32_t>(*calcInt(*node));
  if (const ConfigNode* node = findUserValue(config, "episode.max_steps"))
    options.max_episode_steps = static_cast<uint32_t>(*calcInt(*node));
  if (const ConfigNode* node = findUserValue(config, "control.controller"))
    options.controller = node->scalar;
  // An empty controller_config that nobody but the built-in layer wrote
  // leaves the task's; anything else (null included: "none") is passed on.
  const ConfigNode* controller_config = config.findPath("control.controller_config");
  if (controller_config != nullptr &&
      !isOnlyFrom(*controller_config, ConfigLayer::TaskDescription) &&
      !(controller_config->isMap() && controller_config->entries.empty() &&
        controller_config->origin.layer == ConfigLayer::Builtin)) {
    const bool empty = controller_config->isNull() || controller_config->entries.empty();
    options.controller_config = empty ? "{}" : formatConfig(*controller_config);
  }
  const ConfigNode* task = config.find("task");
  if (task != nullptr && task->isMap() && !task->entries.empty())
    options.task_config = formatConfig(*task);
  calcRenderOptions(config, options.observation);

  // -- observation ------------------------------------------------------------
  // The schema allows only the modes' names.
  options.observation.mode = *findObservationMode(getPath(config, "observation.mode").scalar);
  options.observation.rgb_dtype = *findRgbDtype(getPath(config, "observation.rgb_dtype").scalar);
  PointCloudSampling& sampling = options.observation.pointcloud;
  sampling.per_mask = uint32_t(*calcInt(getPath(config, "observation.pointcloud.per_mask")));
  sampling.masked_total = uint32_t(*calcInt(getPath(config, "observation.pointcloud.masked_total")));
  sampling.total = uint32_t(*calcInt(getPath(config, "observation.pointcloud.total")));
  sampling.ground_height = float(getNumber(config, "observation.pointcloud.ground_height"));
  sampling.pad = *calcBool(getPath(config, "observation.pointcloud.pad"));
  if (sampling.masked_total > sampling.total) {
    const ConfigNode& node = getPath(config, "observation.pointcloud.masked_total");
    throw ConfigError(node.origin.describe() + ": observation.pointcloud.masked_total: " +
                      node.scalar + " exceeds observation.pointcloud.total (" +
                      getPath(config, "observation.pointcloud.total").scalar + ")");
  }
  return options;
}

std::string annotatePluginError(const ConfigNode& config, const std::string& message) {
  std::string notes;
  for (const char* section : {"task", "control.controller_config"}) {
    const ConfigNode* map = config.findPath(section);
    if (map == nullptr || !map->isMap()) continue;
    for (const ConfigEntry& e : map->entries)
      if (containsWord(message, e.key))
        notes += (notes.empty() ? "" : "; ") + std::string(section) + "." + e.key + " is set at " +
                 e.value.origin.describe();
  }
  return notes.empty() ? message : message + " [" + notes + "]";
}

}  // namespace manibench
