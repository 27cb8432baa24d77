// The YAML configuration: parsing with origins, layering, the schema's
// errors (file, line and key path), command-line overrides, the options it
// gives. That a configuration really changes a real Environment is
// config_environment_test.cpp.
#include <manibench/config.hpp>
#include <manibench/environment.hpp>

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <tuple>

#include "config_files.hpp"
#include "test_support.hpp"

namespace manibench {
namespace {

using config_test::TempFile;

// The ConfigError message of `body`; fails the test when nothing is thrown.
template <class Body>
std::string getConfigError(Body&& body) {
  return testing::catchMessage<ConfigError>(body);
}

bool startsWith(const std::string& text, const std::string& prefix) {
  return text.rfind(prefix, 0) == 0;
}
using testing::contains;

// The merged configuration of one user file over the built-in defaults.
ConfigNode calcWithFile(const TempFile& file) { return calcConfig(nullptr, {{file.path()}, {}}); }

// ---- parsing ------------------------------------------------------------------

TEST(Config, ParsingKeepsFileAndLineOfEveryValue) {
  const ConfigNode node = parseConfig("physics:\n  accuracy: 0.001\n\n  gravity: [0, 0, -1]\nname: \"5\"\n",
                                      "my.yaml");
  ASSERT_TRUE(node.isMap());
  const ConfigNode* accuracy = node.findPath("physics.accuracy");
  ASSERT_NE(accuracy, nullptr);
  EXPECT_EQ(accuracy->scalar, "0.001");
  EXPECT_EQ(accuracy->origin.describe(), "my.yaml:2");
  EXPECT_EQ(accuracy->origin.layer, ConfigLayer::File);
  EXPECT_EQ(node.findPath("physics.gravity")->items[2].origin.describe(), "my.yaml:4");
  // Quoted scalars are strings: not numbers, whatever they look like.
  EXPECT_TRUE(node.find("name")->quoted);
  EXPECT_FALSE(calcNumber(*node.find("name")));
  EXPECT_EQ(*calcNumber(*accuracy), 0.001);
}

TEST(Config, ScalarsFollowTheYamlCoreSchema) {
  auto scalar = [](const std::string& text) { return *parseConfig("v: " + text, "t").find("v"); };
  EXPECT_EQ(*calcInt(scalar("42")), 42);
  EXPECT_EQ(*calcInt(scalar("-7")), -7);
  EXPECT_EQ(*calcInt(scalar("0x10")), 16);
  EXPECT_FALSE(calcInt(scalar("1.5")));
  EXPECT_FALSE(calcInt(scalar("99999999999999999999")));
  EXPECT_EQ(*calcNumber(scalar("1e6")), 1e6);
  EXPECT_EQ(*calcNumber(scalar("-.5")), -0.5);
  EXPECT_TRUE(std::isinf(*calcNumber(scalar(".inf"))));
  EXPECT_FALSE(calcNumber(scalar("1.2.3")));
  EXPECT_FALSE(calcNumber(scalar("ten")));
  EXPECT_EQ(*calcBool(scalar("true")), true);
  EXPECT_EQ(*calcBool(scalar("False")), false);
  EXPECT_FALSE(calcBool(scalar("yes")));  // YAML 1.1 only
  EXPECT_TRUE(scalar("~").isNull());
  EXPECT_TRUE(scalar("null").isNull());
}

TEST(Config, MalformedYamlNamesFileAndLine) {
  const TempFile file("physics:\n  accuracy: 0.1\n  gravity: [0, 0\n");
  const std::string message = getConfigError([&] { loadConfigFile(file.path()); });
  EXPECT_TRUE(startsWith(message, file.path() + ":")) << message;
  EXPECT_TRUE(contains(message, "malformed YAML")) << message;
  // yaml-cpp reports the unclosed flow sequence where it gives up: line 3 or 4.
  EXPECT_TRUE(contains(message, file.path() + ":3:") || contains(message, file.path() + ":4:")) << message;
}

TEST(Config, DuplicateKeysAndSecondDocumentsAreErrors) {
  const TempFile duplicate("physics:\n  accuracy: 0.1\n  accuracy: 0.2\n");
  EXPECT_EQ(getConfigError([&] { loadConfigFile(duplicate.path()); }),
            duplicate.path() + ":3: duplicate key 'accuracy'");
  const TempFile two("physics: {}\n---\ncameras: []\n");
  EXPECT_TRUE(startsWith(getConfigError([&] { loadConfigFile(two.path()); }), two.path() + ":"));
}

TEST(Config, UnreadableFileIsAClearError) {
  const std::string message = getConfigError([] { loadConfigFile("/nonexistent/dir/my.yaml"); });
  EXPECT_EQ(message, "cannot read configuration file '/nonexistent/dir/my.yaml': No such file or directory");
}

// Hostile files end quickly with the reason: an alias bomb ("billion
// laughs", 10 levels of 9 aliases: 3.9e8 values expanded), 3000-deep
// nesting, a directory.
TEST(Config, HostileFilesAreRefusedQuicklyWithTheReason) {
  std::string bomb = "a0: &a0 [x, x, x, x, x, x, x, x, x]\n";
  for (int i = 1; i < 10; ++i) {
    bomb += "a" + std::to_string(i) + ": &a" + std::to_string(i) + " [";
    for (int k = 0; k < 9; ++k) bomb += (k ? ", *a" : "*a") + std::to_string(i - 1);
    bomb += "]\n";
  }
  bomb += "task: {bomb: *a9}\n";
  const TempFile bomb_file(bomb);
  const std::string expanded = getConfigError([&] { loadConfigFile(bomb_file.path()); });
  EXPECT_TRUE(startsWith(expanded, bomb_file.path() + ":")) << expanded;
  EXPECT_TRUE(contains(expanded, "more than 100000 values")) << expanded;

  const TempFile deep("task: " + std::string(3000, '[') + std::string(3000, ']') + "\n");
  const std::string nested = getConfigError([&] { loadConfigFile(deep.path()); });
  EXPECT_TRUE(startsWith(nested, deep.path() + ":1:")) << nested;
  EXPECT_TRUE(contains(nested, "nested deeper than 64 levels")) << nested;

  // yaml-cpp 0.7 never returns from these (found by tests/fuzz).
  for (const char* text : {",\n", "# a comment\n  , 2, 3]\n", "a: 1\n---\n, x\n"}) {
    const TempFile comma(text);
    const std::string message = getConfigError([&] { loadConfigFile(comma.path()); });
    EXPECT_TRUE(contains(message, "a document cannot start with ','")) << message;
  }

  const std::string directory = getConfigError([] { loadConfigFile("/tmp"); });
  EXPECT_EQ(directory, "configuration file '/tmp' is a directory");
}

TEST(Config, EmptyFileIsAnEmptyLayer) {
  const TempFile file("# nothing yet\n");
  EXPECT_TRUE(isSameConfig(calcWithFile(file), calcConfig(nullptr, {})));
}

// ---- merging -------------------------------------------------------------------

TEST(Config, MapsMergeDeeplyWhileListsAndScalarsReplace) {
  ConfigNode base = parseConfig(
      "physics:\n  accuracy: 0.01\n  contact:\n    default: {stiffness: 1, dissipation: 2}\n"
      "cameras: [{name: a}, {name: b}]\n",
      "base.yaml");
  const ConfigNode layer = parseConfig(
      "physics:\n  contact:\n    default: {dissipation: 3}\ncameras: [{name: c}]\n", "layer.yaml");
  mergeConfig(base, layer);
  EXPECT_EQ(base.findPath("physics.accuracy")->scalar, "0.01");
  EXPECT_EQ(base.findPath("physics.contact.default.stiffness")->scalar, "1");
  EXPECT_EQ(base.findPath("physics.contact.default.dissipation")->scalar, "3");
  EXPECT_EQ(base.findPath("physics.contact.default.dissipation")->origin.describe(), "layer.yaml:3");
  ASSERT_EQ(base.find("cameras")->items.size(), 1u);
  EXPECT_EQ(base.find("cameras")->items[0].find("name")->scalar, "c");
  // null replaces a whole map.
  mergeConfig(base, parseConfig("physics:\n  contact: null\n", "clear.yaml"));
  EXPECT_TRUE(base.findPath("physics.contact")->isNull());
  EXPECT_EQ(base.findPath("physics.accuracy")->scalar, "0.01");
}

TaskDescription makeTaskDescription(const std::string& default_config) {
  TaskDescription task;
  task.name = "Fake-v0";
  task.default_controller = "joint_velocity";
  task.controller_config = "damping: 50\ncutoff_hz: 10\n";
  task.control_frequency = 100;
  task.frame_skip = 5;
  task.max_episode_steps = 200;
  task.default_config = default_config;
  return task;
}

TEST(Config, LayersApplyInOrderOfPrecedence) {
  const TaskDescription task = makeTaskDescription(
      "physics:\n  accuracy: 0.02\n  integrator: rk_merson\n  default_density: 500\n"
      "control:\n  frame_skip: 4\n");
  const TempFile first("physics:\n  accuracy: 0.03\n  default_density: 600\n", "first.yaml");
  const TempFile second("physics:\n  accuracy: 0.04\n", "second.yaml");
  const ConfigNode config = calcConfig(
      &task, {{first.path(), second.path()},
              {"physics.accuracy=0.05", "physics.accuracy=0.06", "control.frequency=50"}});
  auto origin = [&](const std::string& path) { return config.findPath(path)->origin.describe(); };
  auto value = [&](const std::string& path) { return config.findPath(path)->scalar; };
  EXPECT_EQ(config.findPath("physics.gravity")->items.size(), 3u);
  EXPECT_EQ(origin("physics.gravity"), "built-in defaults:10");
  EXPECT_EQ(value("episode.max_steps"), "200");
  EXPECT_EQ(origin("episode.max_steps"), "task Fake-v0 description");
  EXPECT_EQ(value("control.frame_skip"), "4");
  EXPECT_EQ(origin("control.frame_skip"), "task Fake-v0 defaults:6");
  EXPECT_EQ(value("physics.integrator"), "rk_merson");
  EXPECT_EQ(value("physics.default_density"), "600");
  EXPECT_EQ(origin("physics.default_density"), first.path() + ":3");
  EXPECT_EQ(value("physics.accuracy"), "0.06");
  EXPECT_EQ(origin("physics.accuracy"), "--set physics.accuracy=0.06");
  EXPECT_EQ(value("control.frequency"), "50");
  EXPECT_EQ(value("control.controller_config.damping"), "50");

  // Without the overrides, the later file wins over the earlier one.
  const ConfigNode files_only = calcConfig(&task, {{first.path(), second.path()}, {}});
  EXPECT_EQ(files_only.findPath("physics.accuracy")->scalar, "0.04");
  const ConfigNode reversed = calcConfig(&task, {{second.path(), first.path()}, {}});
  EXPECT_EQ(reversed.findPath("physics.accuracy")->scalar, "0.03");
}

TEST(Config, TaskLayerErrorsNameTheTask) {
  const TaskDescription task = makeTaskDescription("physics:\n  integrater: cpodes\n");
  EXPECT_EQ(getConfigError([&] { calcConfig(&task, {}); }),
            "task Fake-v0 defaults:2: physics.integrater: unknown key (did you mean physics.integrator?)");
  TaskDescription bad_controller = makeTaskDescription("");
  bad_controller.controller_config = "[1, 2]";
  EXPECT_TRUE(contains(getConfigError([&] { calcConfig(&bad_controller, {}); }),
                       "control.controller_config"));
}

// ---- schema errors: file, line, key path -------------------------------------------

struct ErrorCase {
  const char* yaml;
  const char* expected;  // after "<file>:"
};

TEST(Config, EveryKindOfSchemaErrorNamesFileLineAndKey) {
  const ErrorCase cases[] = {
      {"physics:\n  accuracy: 5\n", "2: physics.accuracy: must be in (0, 1], got 5"},
      {"physics:\n  accuracy: 0\n", "2: physics.accuracy: must be in (0, 1], got 0"},
      {"physics:\n  accuracy: fast\n", "2: physics.accuracy: must be a number, got fast"},
      {"physics:\n  accuracy: \"0.1\"\n",
       "2: physics.accuracy: must be a number, got the string \"0.1\""},
      {"physics:\n  acuracy: 0.1\n", "2: physics.acuracy: unknown key (did you mean physics.accuracy?)"},
      {"# comment\naccuracy: 0.1\n", "2: accuracy: unknown key (did you mean physics.accuracy?)"},
      {"physics:\n  integrator: euler\n",
       "2: physics.integrator: must be one of implicit_euler, cpodes, rk_merson, semi_explicit_euler, got euler"},
      {"physics:\n  fixed_step: 1\n", "2: physics.fixed_step: must be in (0, 0.1], got 1"},
      {"physics:\n  self_collision:\n    arm: yes\n",
       "3: physics.self_collision.arm: must be true or false, got yes"},
      {"physics:\n  contact:\n    ground: {dynamic_friction: 0.9}\n",
       "3: physics.contact.ground.dynamic_friction: must not exceed static_friction (0.8, from "
       "built-in defaults:24), got 0.9"},
      {"physics:\n  gravity: [0, 0]\n",
       "2: physics.gravity: must be a list of 3 numbers [x, y, z], got a list of 2"},
      {"physics:\n  gravity:\n    - 0\n    - 0\n    - down\n",
       "5: physics.gravity[2]: must be a number, got down"},
      {"physics: 3\n", "1: physics: must be a map, got 3"},
      {"control:\n  frame_skip: 2.5\n", "2: control.frame_skip: must be an integer, got 2.5"},
      {"control:\n  frame_skip: 0\n", "2: control.frame_skip: must be in [1, 100000], got 0"},
      {"episode:\n  max_steps: -1\n", "2: episode.max_steps: must be in [1, 1e+09], got -1"},
      {"control:\n  controller: [a]\n", "2: control.controller: must be a string, got a list of 1"},
      {"task: 5\n", "1: task: must be a map, got 5"},
      {"physics:\n  contact:\n    default:\n      static_friction: -0.1\n",
       "4: physics.contact.default.static_friction: must be >= 0, got -0.1"},
      {"physics:\n  contact:\n    bodies:\n      - articulation: arm\n        link: forearm\n"
       "        stifness: 1e5\n",
       "6: physics.contact.bodies[0].stifness: unknown key (did you mean "
       "physics.contact.bodies[0].stiffness?)"},
      {"physics:\n  contact:\n    bodies:\n      - link: forearm\n        static_friction: 1\n",
       "4: physics.contact.bodies[0]: missing required key 'articulation' (the articulation's name "
       "in the scene (as the task added it))"},
      {"physics:\n  contact:\n    default: {static_friction: 0.5, dynamic_friction: 0.7}\n",
       "3: physics.contact.default.dynamic_friction: must not exceed static_friction (0.5, from "},
      {"cameras:\n  - name: head\n    width: 0\n", "3: cameras[0].width: must be in [1, 16384], got 0"},
      {"cameras:\n  - name: head\n    fovy: 3.5\n", "3: cameras[0].fovy: must be in (0, 3.14159), got 3.5"},
      {"cameras:\n  - name: head\n    near: 2\n    far: 1\n",
       "4: cameras[0].far: near (2) must be less than far (1)"},
      {"cameras:\n  - name: a\n  - name: a\n", "3: cameras[1].name: duplicate camera name 'a'"},
      {"cameras:\n  - name: a\n    link: hand\n",
       "3: cameras[0].link: a mount link needs the articulation it belongs to"},
      {"cameras:\n  - name: a\n    pose: {position: [0, 0, 1], rotation: [0, 0, 0]}\n",
       "3: cameras[0].pose.rotation: unknown key"},
      {"cameras:\n  name: a\n", "2: cameras: must be a list of maps, got a map"},
      {"cameras:\n  - 3\n", "2: cameras[0]: must be a map, got 3"},
      {"lights:\n  directional:\n    - direction: [0, 0, 0]\n",
       "3: lights.directional[0].direction: must not be [0, 0, 0]"},
      {"lights:\n  ambient: [0.1, 0.1]\n",
       "2: lights.ambient: must be a list of 3 or 4 numbers [r, g, b(, a)], got a list of 2"},
      {"materials:\n  wood:\n    color: [1.5, 0, 0]\n",
       "3: materials.wood.color[0]: must be in [0, 1], got 1.5"},
      {"materials:\n  wood:\n    roughnes: 0.3\n",
       "3: materials.wood.roughnes: unknown key (did you mean materials.wood.roughness?)"},
      {"layouts:\n  robot:\n    distance: [1.8, 1.6]\n",
       "3: layouts.robot.distance: min must not exceed max, got [1.8, 1.6]"},
      {"layouts:\n  robot:\n    yaw_noise: 4\n", "3: layouts.robot.yaw_noise: must be in [0, 3.14159], got 4"},
      {"- physics\n", "1: (top level): a configuration must be a map of keys, got a list of 1"},
  };
  for (const ErrorCase& c : cases) {
    const TempFile file(c.yaml);
    const std::string message = getConfigError([&] { calcWithFile(file); });
    EXPECT_TRUE(startsWith(message, file.path() + ":" + c.expected))
        << "YAML:\n" << c.yaml << "message:  " << message << "\nexpected: " << file.path() << ":"
        << c.expected;
  }
}

TEST(Config, RelationsAreCheckedAcrossLayers) {
  // Each layer is fine alone; together dynamic friction exceeds static.
  const TempFile file("physics:\n  contact:\n    default:\n      static_friction: 0.5\n");
  const std::string message = getConfigError([&] { calcWithFile(file); });
  EXPECT_EQ(message, file.path() +
                         ":4: physics.contact.default.static_friction: must be at least "
                         "dynamic_friction (0.6, from built-in defaults:25), got 0.5");
  // A body inherits the default's static friction.
  const TempFile body(
      "physics:\n  contact:\n    bodies:\n      - {articulation: arm, link: tip, dynamic_friction: 0.9}\n");
  EXPECT_TRUE(startsWith(getConfigError([&] { calcWithFile(body); }),
                         body.path() + ":4: physics.contact.bodies[0].dynamic_friction: must not exceed "
                                       "static_friction (0.8, from built-in defaults:24)"));
}

TEST(Config, ListItemsGetTheirDefaults) {
  const TempFile file("cameras:\n  - name: head\n    width: 64\n    pose: {position: [1, 2, 3]}\n");
  const ConfigNode config = calcWithFile(file);
  const ConfigNode& camera = config.find("cameras")->items.at(0);
  EXPECT_EQ(camera.find("width")->scalar, "64");
  EXPECT_EQ(camera.find("height")->scalar, "160");
  EXPECT_EQ(camera.find("height")->origin.describe(), "built-in defaults");
  EXPECT_EQ(camera.findPath("pose.rpy")->items.size(), 3u);
  EXPECT_EQ(camera.findPath("pose.position")->items[2].scalar, "3");
  EXPECT_TRUE(camera.find("articulation")->isNull());
}

// ---- command-line overrides ----------------------------------------------------------

TEST(Config, OverridesParseValuesAsYaml) {
  const ConfigNode scalar = parseConfigOverride("physics.accuracy=0.001");
  EXPECT_EQ(scalar.findPath("physics.accuracy")->scalar, "0.001");
  EXPECT_EQ(scalar.findPath("physics.accuracy")->origin.describe(), "--set physics.accuracy=0.001");
  EXPECT_EQ(scalar.findPath("physics.accuracy")->origin.layer, ConfigLayer::Override);
  const ConfigNode vector = parseConfigOverride("physics.gravity=[0, 0, -1.62]");
  EXPECT_EQ(vector.findPath("physics.gravity")->items.size(), 3u);
  const ConfigNode map = parseConfigOverride("task={reach_tolerance: 0.05, hold_steps: 3}");
  EXPECT_EQ(map.findPath("task.hold_steps")->scalar, "3");
  EXPECT_TRUE(parseConfigOverride("control.frequency=").findPath("control.frequency")->isNull());
  // '=' inside the value belongs to the value.
  EXPECT_EQ(parseConfigOverride("task.expr=a=b").findPath("task.expr")->scalar, "a=b");
}

TEST(Config, BadOverridesAreErrorsNamingTheOverride) {
  EXPECT_EQ(getConfigError([] { parseConfigOverride("physics.accuracy"); }),
            "--set physics.accuracy: expected KEY=VALUE, e.g. --set physics.accuracy=0.001");
  EXPECT_TRUE(startsWith(getConfigError([] { parseConfigOverride("physics..accuracy=1"); }),
                         "--set physics..accuracy=1: the key path 'physics..accuracy' has an empty part"));
  EXPECT_TRUE(startsWith(getConfigError([] { parseConfigOverride("cameras[0].width=5"); }),
                         "--set cameras[0].width=5: list items cannot be set one by one"));
  EXPECT_TRUE(startsWith(getConfigError([] { parseConfigOverride("physics.acc uracy=5"); }),
                         "--set physics.acc uracy=5: the key path"));
  EXPECT_TRUE(startsWith(getConfigError([] { parseConfigOverride("physics.gravity=[0, 0"); }),
                         "--set physics.gravity=[0, 0: malformed YAML"));
  EXPECT_EQ(getConfigError([] { calcConfig(nullptr, {{}, {"physics.accuracy=5"}}); }),
            "--set physics.accuracy=5: physics.accuracy: must be in (0, 1], got 5");
  EXPECT_EQ(getConfigError([] { calcConfig(nullptr, {{}, {"physics.acuracy=0.1"}}); }),
            "--set physics.acuracy=0.1: physics.acuracy: unknown key (did you mean physics.accuracy?)");
  EXPECT_EQ(getConfigError([] { calcConfig(nullptr, {{}, {"physics=3"}}); }),
            "--set physics=3: physics: must be a map, got 3");
}

// ---- suggestions -------------------------------------------------------------------------

TEST(Config, NearestKeyIsSuggestedForTypos) {
  EXPECT_EQ(findNearestConfigKey("physics.acuracy"), "physics.accuracy");
  EXPECT_EQ(findNearestConfigKey("physics.integrater"), "physics.integrator");
  EXPECT_EQ(findNearestConfigKey("control.frame-skip"), "control.frame_skip");
  EXPECT_EQ(findNearestConfigKey("physcs"), "physics");
  EXPECT_EQ(findNearestConfigKey("accuracy"), "physics.accuracy");         // wrong level
  EXPECT_EQ(findNearestConfigKey("cameras[3].widht"), "cameras[3].width");  // inside a list
  EXPECT_EQ(findNearestConfigKey("physics.accuracy"), "physics.accuracy");  // known
  EXPECT_EQ(findNearestConfigKey("physics.zzzzzzzzzz"), "");                // nothing close
}

// ---- the schema, the built-in layer, the docs ----------------------------------------------

TEST(Config, BuiltinDefaultsMatchPhysicsSettingsAndCoverTheSchema) {
  const ConfigNode config = calcConfig(nullptr, {});
  const EnvironmentOptions options = calcEnvironmentOptions(config);
  const PhysicsSettings expected;
  EXPECT_EQ(options.physics.gravity_z, expected.gravity_z);
  EXPECT_EQ(options.physics.integrator, expected.integrator);
  EXPECT_EQ(options.physics.implicit_step, expected.implicit_step);
  EXPECT_EQ(options.physics.accuracy, expected.accuracy);
  EXPECT_EQ(options.physics.fixed_step, expected.fixed_step);
  EXPECT_EQ(options.physics.friction_stiffness, expected.friction_stiffness);
  EXPECT_EQ(options.physics.friction_damping, expected.friction_damping);
  const ContactMaterial& material = options.physics.default_material;
  EXPECT_EQ(material.stiffness, expected.default_material.stiffness);
  EXPECT_EQ(material.dissipation, expected.default_material.dissipation);
  EXPECT_EQ(material.static_friction, expected.default_material.static_friction);
  EXPECT_EQ(material.dynamic_friction, expected.default_material.dynamic_friction);
  EXPECT_EQ(material.viscous_friction, expected.default_material.viscous_friction);
  EXPECT_EQ(options.physics.default_density, expected.default_density);
  EXPECT_EQ(options.physics.divergence_speed_limit, expected.divergence_speed_limit);
  EXPECT_EQ(options.physics.default_joint_damping, expected.default_joint_damping);
  // Nothing asks to change the task's timing, controller or configuration.
  EXPECT_FALSE(options.control_frequency);
  EXPECT_FALSE(options.frame_skip);
  EXPECT_FALSE(options.max_episode_steps);
  EXPECT_EQ(options.controller, "");
  EXPECT_EQ(options.controller_config, "");
  EXPECT_EQ(options.task_config, "");
  EXPECT_FALSE(options.ground_material);
  EXPECT_TRUE(options.contact_materials.empty());
  EXPECT_TRUE(options.self_collision.empty());
  // Every key outside lists, named maps and the ground's optional fields
  // (left out: the default material's) has a built-in value.
  for (const ConfigKey& key : getConfigSchema()) {
    if (key.path.find("[]") == std::string::npos && key.path.find('*') == std::string::npos &&
        key.path.rfind("physics.contact.ground.", 0) != 0) {
      EXPECT_NE(config.findPath(key.path), nullptr) << key.path << " has no built-in default";
    }
  }
}

// The observation keys' built-in values are ObservationOptions' defaults, so
// that an environment built from EnvironmentOptions{} observes as one built
// from an empty configuration.
TEST(Config, BuiltinDefaultsMatchObservationOptions) {
  const ObservationOptions built_in =
      calcEnvironmentOptions(calcConfig(nullptr, {})).observation;
  const ObservationOptions expected;
  // Lights: the ambient term and the point lights agree; the directional
  // ones do not (the built-in layer has one sun, LightingSpec ManiSkill's
  // two lights), which only a hand-built environment in a visual mode sees.
  auto fields = [](const ObservationOptions& o) {
    const PointCloudSampling& s = o.pointcloud;
    return std::make_tuple(o.mode, o.cameras.size(), s.per_mask, s.masked_total, s.total,
                           s.ground_height, s.pad, o.lighting.ambient.x(), o.lighting.ambient.y(),
                           o.lighting.ambient.z(), o.lighting.point.size());
  };
  EXPECT_EQ(fields(built_in), fields(expected));
}

TEST(Config, DocsDescribeEveryKey) {
  std::ifstream in(std::string(MANIBENCH_TEST_SOURCE_DIR) + "/docs/configuration.md");
  ASSERT_TRUE(in) << "docs/configuration.md is missing";
  std::stringstream text;
  text << in.rdbuf();
  for (const ConfigKey& key : getConfigSchema())
    EXPECT_TRUE(contains(text.str(), "`" + key.path + "`")) << key.path << " is not in the docs";
}

TEST(Config, FormattedConfigReadsBackTheSame) {
  const TempFile file(
      "physics:\n  accuracy: 0.001\ntask:\n  label: \"007\"\n  weird: \"a: b # c\"\n  list: [1, [2, 3]]\n"
      "cameras:\n  - name: a\n    far: 20\n");
  const ConfigNode config = calcWithFile(file);
  for (bool with_origins : {false, true}) {
    const ConfigNode back = parseConfig(formatConfig(config, with_origins), "printed");
    EXPECT_TRUE(isSameConfig(config, back)) << formatConfig(config, with_origins);
  }
  EXPECT_TRUE(contains(formatConfig(config, true), "# " + file.path() + ":2"));
}

// ---- options ------------------------------------------------------------------------------

TEST(Config, OptionsCarryOnlyWhatLayersAboveTheTaskDescriptionSet) {
  const TaskDescription task = makeTaskDescription("episode:\n  max_steps: 150\n");
  const EnvironmentOptions described = calcEnvironmentOptions(calcConfig(&task, {}));
  EXPECT_FALSE(described.control_frequency);  // the task's own value applies
  EXPECT_EQ(described.max_episode_steps, 150u);
  EXPECT_EQ(described.controller, "");
  EXPECT_EQ(described.controller_config, "");

  const EnvironmentOptions set = calcEnvironmentOptions(calcConfig(
      &task, {{}, {"control.frequency=50", "control.frame_skip=2", "control.controller=joint_position",
                   "control.controller_config={kp: 3}", "task={reach_tolerance: 0.1}"}}));
  EXPECT_EQ(set.control_frequency, 50.0);
  EXPECT_EQ(set.frame_skip, 2u);
  EXPECT_EQ(set.controller, "joint_position");
  // The merged controller configuration: the task's keys and the new one.
  const ConfigNode controller = parseConfig(set.controller_config, "c");
  EXPECT_EQ(controller.find("damping")->scalar, "50");
  EXPECT_EQ(controller.find("kp")->scalar, "3");
  EXPECT_EQ(parseConfig(set.task_config, "t").find("reach_tolerance")->scalar, "0.1");

  // null clears the controller configuration instead of falling back to the task's.
  const EnvironmentOptions cleared =
      calcEnvironmentOptions(calcConfig(&task, {{}, {"control.controller_config=null"}}));
  EXPECT_EQ(cleared.controller_config, "{}");

  // The scene's gravity is vertical: sideways gravity is refused, named.
  EXPECT_EQ(getConfigError([] {
              calcEnvironmentOptions(calcConfig(nullptr, {{}, {"physics.gravity=[1, 0, -9.81]"}}));
            }),
            "--set physics.gravity=[1, 0, -9.81]: physics.gravity: the scene supports vertical gravity "
            "only; x and y must be 0, got [1, 0, -9.81]");
}

TEST(Config, ContactMaterialsMapOntoTheSceneSettings) {
  const TempFile file(
      "physics:\n"
      "  contact:\n"
      "    default: {stiffness: 3.0e+5, static_friction: 0.5, dynamic_friction: 0.4}\n"
      "    ground: {static_friction: 1.0}\n"
      "    bodies:\n"
      "      - {articulation: arm}\n"
      "      - {articulation: arm, link: forearm, dynamic_friction: 0.1, viscous_friction: 0.2}\n"
      "  self_collision: {arm: true}\n");
  const EnvironmentOptions options = calcEnvironmentOptions(calcWithFile(file));
  EXPECT_EQ(options.physics.default_material.stiffness, 3e5);
  EXPECT_EQ(options.physics.default_material.dissipation, ContactMaterial{}.dissipation);
  ASSERT_TRUE(options.ground_material);
  EXPECT_EQ(options.ground_material->static_friction, 1.0);
  EXPECT_EQ(options.ground_material->dynamic_friction, 0.4);  // the default's
  ASSERT_EQ(options.contact_materials.size(), 2u);
  EXPECT_EQ(options.contact_materials[0].link, "");  // every link
  EXPECT_EQ(options.contact_materials[0].material.static_friction, 0.5);
  const BodyContactMaterial& forearm = options.contact_materials[1];
  EXPECT_EQ(forearm.articulation, "arm");
  EXPECT_EQ(forearm.link, "forearm");
  EXPECT_EQ(forearm.material.stiffness, 3e5);
  EXPECT_EQ(forearm.material.static_friction, 0.5);
  EXPECT_EQ(forearm.material.dynamic_friction, 0.1);
  EXPECT_EQ(forearm.material.viscous_friction, 0.2);
  EXPECT_EQ(forearm.source, file.path() + ":7: physics.contact.bodies");
  ASSERT_EQ(options.self_collision.size(), 1u);
  EXPECT_EQ(options.self_collision[0].articulation, "arm");
  EXPECT_TRUE(options.self_collision[0].enabled);
}

}  // namespace
}  // namespace manibench
