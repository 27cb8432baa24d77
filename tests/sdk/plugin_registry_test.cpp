// PluginRegistry against real shared libraries: the fixtures of
// tests/fixtures (most of them deliberately broken) and the build tree's
// plugins. Every refusal must name the file and the precise values, leave
// the registry usable, and never let an exception cross the C ABI.
#include <manibench/abi.h>
#include <manibench/plugin_instances.hpp>
#include <manibench/plugin_registry.hpp>

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using manibench::LoadFailure;
using manibench::PluginEntry;
using manibench::PluginError;
using manibench::PluginKind;
using manibench::PluginRegistry;
using manibench::PolicyEpisode;
using manibench::PolicyInstance;
using manibench::PolicyLayout;

const std::string kFixtureDir = MANIBENCH_TEST_FIXTURE_DIR;
const std::string kBuildPluginDir = MANIBENCH_TEST_BUILD_PLUGIN_DIR;

// ---- helpers ------------------------------------------------------------

std::string fixtureFile(const std::string& fixture) { return "lib" + fixture + ".so"; }
std::string fixturePath(const std::string& fixture) {
  return kFixtureDir + "/" + fixtureFile(fixture);
}

::testing::AssertionResult contains(const std::string& text, const std::string& part) {
  if (text.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "\"" << part << "\" not found in: " << text;
}

// `number` appears in `text` as a whole number (not as part of a longer one).
::testing::AssertionResult containsNumber(const std::string& text, std::size_t number) {
  const std::string digits = std::to_string(number);
  for (std::size_t at = text.find(digits); at != std::string::npos;
       at = text.find(digits, at + 1)) {
    const bool digit_before = at > 0 && std::isdigit(static_cast<unsigned char>(text[at - 1]));
    const std::size_t end = at + digits.size();
    const bool digit_after =
        end < text.size() && std::isdigit(static_cast<unsigned char>(text[end]));
    if (!digit_before && !digit_after) return ::testing::AssertionSuccess();
  }
  return ::testing::AssertionFailure() << "number " << number << " not found in: " << text;
}

// Loads `path`, which must be refused; returns the message.
std::string loadError(PluginRegistry& registry, const std::string& path) {
  try {
    registry.loadLibrary(path);
  } catch (const PluginError& e) {
    return e.what();
  }
  ADD_FAILURE() << "loading " << path << " was not refused";
  return "";
}

std::string joined(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

std::string describeFailures(const PluginRegistry& registry) {
  std::string out;
  for (const LoadFailure& f : registry.getFailures()) out += "\n  " + f.path + ": " + f.message;
  return out;
}

bool isLoaded(const PluginRegistry& registry, const fs::path& file) {
  for (const auto& library : registry.getLibraries()) {
    std::error_code ec;
    if (fs::equivalent(library.path, file, ec)) return true;
  }
  return false;
}

std::vector<fs::path> listPlugins(const std::string& dir) {
  std::vector<fs::path> out;
  std::error_code ec;
  for (const auto& item : fs::directory_iterator(dir, ec))
    if (item.path().extension() == ".so") out.push_back(item.path());
  return out;
}

struct ErrorBuffer {
  char text[512];
  mb_error err{text, sizeof(text)};
  ErrorBuffer() { std::strcpy(text, "untouched"); }
};

// A state-mode policy context and observation, as the host makes them.
mb_policy_context makePolicyContext(const char* task, uint32_t observation_dim,
                                    uint32_t action_dim) {
  mb_policy_context context{};
  context.struct_size = sizeof(context);
  context.task_name = task;
  context.observation_mode = "state";
  context.observation_dim = observation_dim;
  context.action_dim = action_dim;
  return context;
}
mb_observation makeObservation(const double* state, uint32_t dim) {
  mb_observation observation{};
  observation.struct_size = sizeof(observation);
  observation.state = state;
  observation.state_dim = dim;
  return observation;
}

// A zero-action policy (fixture_newer_minor's, the duplicates') works
// through the ABI: create, reset, act writes zeros, destroy.
void expectZeroPolicyWorks(const mb_policy_descriptor& policy) {
  const double state[3] = {0.1, 0.2, 0.3};
  const mb_policy_context context = makePolicyContext("Test-v0", 3, 2);
  ErrorBuffer e;
  mb_policy* handle = nullptr;
  ASSERT_EQ(policy.create("", &context, &handle, &e.err), MB_OK) << e.text;
  ASSERT_NE(handle, nullptr);
  EXPECT_EQ(policy.reset(handle, 7, &e.err), MB_OK) << e.text;
  const mb_observation observation = makeObservation(state, 3);
  double action[2] = {std::numeric_limits<double>::quiet_NaN(), 5.0};
  EXPECT_EQ(policy.act(handle, &observation, action, 2, &e.err), MB_OK) << e.text;
  EXPECT_EQ(action[0], 0.0);
  EXPECT_EQ(action[1], 0.0);
  policy.destroy(handle);
}

// After a refusal the same registry still loads good libraries and resolves
// names: the build tree's plugins ("random" from examples/policies) and the
// forward-compatible fixture.
void expectStillUsable(PluginRegistry& registry) {
  const std::size_t failures_before = registry.getFailures().size();
  const std::vector<fs::path> tree_plugins = listPlugins(kBuildPluginDir);
  if (!tree_plugins.empty()) {
    EXPECT_NO_THROW(registry.loadDirectories({kBuildPluginDir}));
    EXPECT_EQ(registry.getFailures().size(), failures_before)
        << "build-tree plugins refused:" << describeFailures(registry);
    EXPECT_NE(registry.findEntry(PluginKind::Policy, "random"), nullptr)
        << "policies: " << joined(registry.getNames(PluginKind::Policy));
  }
  ASSERT_NO_THROW(registry.loadLibrary(fixturePath("fixture_newer_minor")));
  ASSERT_NO_THROW(registry.getPolicy("newer_minor_policy"));
  expectZeroPolicyWorks(registry.getPolicy("newer_minor_policy"));
}

// A directory under the system temp dir, unique to this test and process.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string("manibench_registry_") + info->test_suite_name() + "_" +
                       info->name() + "_" + std::to_string(::getpid());
    for (char& c : name)
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') c = '_';
    path_ = fs::temp_directory_path() / name;
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const fs::path& path() const { return path_; }
  fs::path makeDir(const std::string& name) const {
    fs::create_directories(path_ / name);
    return path_ / name;
  }

 private:
  fs::path path_;
};

// Sets an environment variable for one test; restores it afterwards.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::string& value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    ::setenv(name, value.c_str(), 1);
  }
  ~ScopedEnv() {
    if (old_) ::setenv(name_, old_->c_str(), 1);
    else ::unsetenv(name_);
  }

 private:
  const char* name_;
  std::optional<std::string> old_;
};

// ---- refused fixtures, one at a time -----------------------------------

struct BrokenFixture {
  const char* fixture;
  std::vector<std::string> words;       // must appear in the message
  std::vector<std::size_t> numbers;     // must appear as whole numbers
  const char* must_not_register = nullptr;  // a name the library declares
  PluginKind kind = PluginKind::Policy;
};

void PrintTo(const BrokenFixture& f, std::ostream* os) { *os << f.fixture; }

std::vector<BrokenFixture> brokenFixtures() {
  return {
      {"fixture_wrong_abi_major", {"ABI 99.0", "ABI " + std::to_string(MB_ABI_MAJOR) + "." + std::to_string(MB_ABI_MINOR)}, {}},
      {"fixture_small_manifest", {"manifest", "struct_size"}, {8, sizeof(mb_manifest)}},
      {"fixture_small_descriptor",
       {"struct_size", "task", "SmallDescriptor-v0"},
       {sizeof(mb_descriptor), offsetof(mb_task_descriptor, get_state)},  // ABI 1.0's size
       "SmallDescriptor-v0",
       PluginKind::Task},
      {"fixture_no_entry", {MB_ENTRY_POINT_NAME}, {}},
      {"fixture_null_name", {"policy", "no name"}, {}},
      {"fixture_unknown_kind", {"unknown kind"}, {42}},
  };
}

class RefusedFixture : public ::testing::TestWithParam<BrokenFixture> {};

TEST_P(RefusedFixture, ThrowsNamingFileAndValuesAndRegistryStaysUsable) {
  const BrokenFixture& f = GetParam();
  const std::string path = fixturePath(f.fixture);
  ASSERT_TRUE(fs::exists(path)) << path << " was not built";

  PluginRegistry registry;
  const std::string message = loadError(registry, path);
  EXPECT_TRUE(contains(message, fixtureFile(f.fixture)));
  for (const std::string& word : f.words) EXPECT_TRUE(contains(message, word));
  for (std::size_t number : f.numbers) EXPECT_TRUE(containsNumber(message, number));
  RecordProperty("message", message);

  // Nothing of the refused library was committed; loadLibrary records no
  // failure (it throws), and asking again refuses again.
  EXPECT_TRUE(registry.getLibraries().empty());
  EXPECT_TRUE(registry.getEntries().empty());
  EXPECT_TRUE(registry.getFailures().empty());
  EXPECT_EQ(loadError(registry, path), message);

  expectStillUsable(registry);
  EXPECT_FALSE(isLoaded(registry, path));
  if (f.must_not_register) {
    EXPECT_EQ(registry.findEntry(f.kind, f.must_not_register), nullptr);
  }
}

INSTANTIATE_TEST_SUITE_P(Fixtures, RefusedFixture, ::testing::ValuesIn(brokenFixtures()),
                         [](const ::testing::TestParamInfo<BrokenFixture>& info) {
                           return std::string(info.param.fixture);
                         });

TEST(PluginRegistry, MissingFileIsRefusedNamingThePath) {
  PluginRegistry registry;
  const std::string path = kFixtureDir + "/libdoes_not_exist.so";
  EXPECT_TRUE(contains(loadError(registry, path), path));
  expectStillUsable(registry);
}

TEST(PluginRegistry, NonElfFileIsRefusedNamingThePath) {
  TempDir temp;
  const fs::path bogus = temp.path() / "libnot_a_library.so";
  std::ofstream(bogus) << "this is not an ELF file\n";
  PluginRegistry registry;
  EXPECT_TRUE(contains(loadError(registry, bogus.string()), "libnot_a_library.so"));
  expectStillUsable(registry);
}

TEST(PluginRegistry, DuplicateNameNamesBothLibrariesAndTheName) {
  PluginRegistry registry;
  ASSERT_NO_THROW(registry.loadLibrary(fixturePath("fixture_duplicate_a")));
  const std::string message = loadError(registry, fixturePath("fixture_duplicate_b"));
  EXPECT_TRUE(contains(message, "duplicate_policy"));
  EXPECT_TRUE(contains(message, fixtureFile("fixture_duplicate_a")));
  EXPECT_TRUE(contains(message, fixtureFile("fixture_duplicate_b")));
  RecordProperty("message", message);

  // The first registration stands, from library a; b was not committed.
  ASSERT_EQ(registry.getLibraries().size(), 1u);
  EXPECT_EQ(registry.getLibraries()[0].name, "fixture_duplicate_a");
  const PluginEntry& entry = registry.getEntry(PluginKind::Policy, "duplicate_policy");
  EXPECT_EQ(entry.library, 0u);
  EXPECT_FALSE(isLoaded(registry, fixturePath("fixture_duplicate_b")));
  expectZeroPolicyWorks(registry.getPolicy("duplicate_policy"));
  expectStillUsable(registry);
}

// ---- directories -------------------------------------------------------

TEST(PluginRegistry, LoadDirectoriesRecordsOneFailurePerBrokenFixture) {
  PluginRegistry registry;
  ASSERT_NO_THROW(registry.loadDirectories({kFixtureDir}));

  // Files load in sorted order, so duplicate_a wins and duplicate_b fails.
  std::vector<std::string> expected_failed;
  for (const BrokenFixture& f : brokenFixtures()) expected_failed.push_back(fixtureFile(f.fixture));
  expected_failed.push_back(fixtureFile("fixture_duplicate_b"));
  std::sort(expected_failed.begin(), expected_failed.end());

  std::vector<std::string> failed;
  for (const LoadFailure& f : registry.getFailures()) {
    failed.push_back(fs::path(f.path).filename().string());
    EXPECT_TRUE(contains(f.message, fs::path(f.path).filename().string()));
  }
  std::sort(failed.begin(), failed.end());
  EXPECT_EQ(failed, expected_failed) << describeFailures(registry);

  // The good ones are registered and work.
  std::vector<std::string> loaded;
  for (const auto& library : registry.getLibraries()) loaded.push_back(library.name);
  std::sort(loaded.begin(), loaded.end());
  EXPECT_EQ(loaded, (std::vector<std::string>{"fixture_duplicate_a", "fixture_newer_minor",
                                              "fixture_pre_controller_policy", "fixture_robot_testbed",
                                              "fixture_throwing_create"}));
  EXPECT_EQ(registry.getNames(PluginKind::Policy),
            (std::vector<std::string>{"duplicate_policy", "newer_minor_policy", "pre_controller_policy",
                                      "throwing_policy"}));
  EXPECT_EQ(registry.getNames(PluginKind::Task),
            (std::vector<std::string>{"RobotTestbed-v0", "Throwing-v0"}));
  EXPECT_EQ(registry.getNames(PluginKind::Controller),
            std::vector<std::string>{"throwing_controller"});
  expectZeroPolicyWorks(registry.getPolicy("newer_minor_policy"));
  expectZeroPolicyWorks(registry.getPolicy("duplicate_policy"));

  // The duplicate's failure names the library that got there first.
  for (const LoadFailure& f : registry.getFailures()) {
    if (fs::path(f.path).filename() == fixtureFile("fixture_duplicate_b")) {
      EXPECT_TRUE(contains(f.message, fixtureFile("fixture_duplicate_a")));
    }
  }

  // Loading the same directory again changes nothing: loaded libraries are
  // skipped, and a build-tree load afterwards still works.
  const std::size_t libraries = registry.getLibraries().size();
  registry.loadDirectories({kFixtureDir});
  EXPECT_EQ(registry.getLibraries().size(), libraries);
  expectStillUsable(registry);
}

TEST(PluginRegistry, UnreadableDirectoryIsRecordedNotThrown) {
  PluginRegistry registry;
  const std::string missing = kFixtureDir + "/no_such_directory";
  ASSERT_NO_THROW(registry.loadDirectories({missing}));
  ASSERT_EQ(registry.getFailures().size(), 1u);
  EXPECT_TRUE(contains(registry.getFailures()[0].message, missing));
  expectStillUsable(registry);
}

// ABI 1.5: a policy with reset_episode learns its episode's task, object
// and seed; one built against 1.4 (its descriptor ends before the field)
// still loads and gets reset with the seed.
TEST(PluginRegistry, APolicyLearnsItsEpisodeAndAnOlderPolicyGetsReset) {
  PluginRegistry registry;
  ASSERT_NO_THROW(registry.loadLibrary(kFixtureDir + "/episode/" + fixtureFile("fixture_episode_policies")));
  EXPECT_EQ(registry.getLibraries().at(0).abi_minor, MB_ABI_MINOR);
  EXPECT_EQ(registry.getEntry(PluginKind::Policy, "pre_episode_echo").descriptor->struct_size,
            offsetof(mb_policy_descriptor, reset_episode));
  PolicyLayout layout;
  layout.task_name = "Test-v0";
  layout.observation_dim = 1;
  layout.action_dim = 3;
  const Eigen::VectorXd observation = Eigen::VectorXd::Zero(1);
  Eigen::VectorXd action;
  PolicyInstance current(registry, "episode_echo", "", layout);
  current.reset(PolicyEpisode{"Test-v0", "42", 1007});
  current.act(observation, 0, action);
  EXPECT_EQ(action, Eigen::Vector3d(1, 7, 42));
  PolicyInstance older(registry, "pre_episode_echo", "", layout);
  older.reset(PolicyEpisode{"Test-v0", "42", 1007});
  older.act(observation, 0, action);
  EXPECT_EQ(action, Eigen::Vector3d(0, 7, -1));
}

TEST(PluginRegistry, NewerMinorIsAcceptedWithItsVersionRecorded) {
  PluginRegistry registry;
  ASSERT_NO_THROW(registry.loadLibrary(fixturePath("fixture_newer_minor")));
  ASSERT_EQ(registry.getLibraries().size(), 1u);
  const auto& library = registry.getLibraries()[0];
  EXPECT_EQ(library.name, "fixture_newer_minor");
  EXPECT_EQ(library.version, "0.0.1");
  EXPECT_EQ(library.abi_major, MB_ABI_MAJOR);
  EXPECT_EQ(library.abi_minor, MB_ABI_MINOR + 1);
  const PluginEntry& entry = registry.getEntry(PluginKind::Policy, "newer_minor_policy");
  EXPECT_EQ(entry.summary, "zero action, from a newer minor ABI");
  EXPECT_GT(entry.descriptor->struct_size, sizeof(mb_policy_descriptor));
  expectZeroPolicyWorks(registry.getPolicy("newer_minor_policy"));
  // Its descriptor of a kind this host does not know was skipped, not fatal.
  EXPECT_EQ(registry.getEntries().size(), 1u);
  EXPECT_TRUE(registry.getFailures().empty());
}

// ---- names -------------------------------------------------------------

TEST(PluginRegistry, UnknownNameListsAvailableNames) {
  PluginRegistry registry;
  registry.loadLibrary(fixturePath("fixture_newer_minor"));
  registry.loadLibrary(fixturePath("fixture_duplicate_a"));
  try {
    registry.getEntry(PluginKind::Policy, "no_such_policy");
    FAIL() << "an unknown name resolved";
  } catch (const PluginError& e) {
    EXPECT_TRUE(contains(e.what(), "no_such_policy"));
    EXPECT_TRUE(contains(e.what(), "newer_minor_policy"));
    EXPECT_TRUE(contains(e.what(), "duplicate_policy"));
  }
  EXPECT_EQ(registry.findEntry(PluginKind::Policy, "no_such_policy"), nullptr);
  // A name of another kind does not resolve either.
  EXPECT_THROW(registry.getTask("newer_minor_policy"), PluginError);
  EXPECT_THROW(registry.getController("duplicate_policy"), PluginError);
  try {
    registry.getTask("NoSuchTask-v0");
    FAIL() << "an unknown task resolved";
  } catch (const PluginError& e) {
    EXPECT_TRUE(contains(e.what(), "NoSuchTask-v0"));
  }
}

TEST(PluginRegistry, UnknownNameMentionsFailedLibraries) {
  PluginRegistry registry;
  registry.loadDirectories({kFixtureDir});
  ASSERT_FALSE(registry.getFailures().empty());
  try {
    registry.getPolicy("no_such_policy");
    FAIL() << "an unknown name resolved";
  } catch (const PluginError& e) {
    EXPECT_TRUE(contains(e.what(), "no_such_policy"));
    EXPECT_TRUE(contains(e.what(), "failed"));
    EXPECT_TRUE(containsNumber(e.what(), registry.getFailures().size()));
  }
}

// ---- search path and de-duplication --------------------------------------

TEST(PluginRegistry, SearchPathOrderAndFirstMatchByFileNameWins) {
  TempDir temp;
  const fs::path dir_a = temp.makeDir("dirA");
  const fs::path dir_b = temp.makeDir("dirB");
  const std::string file = fixtureFile("fixture_newer_minor");
  fs::copy_file(fixturePath("fixture_newer_minor"), dir_a / file);
  fs::copy_file(fixturePath("fixture_newer_minor"), dir_b / file);
  const std::string missing = (temp.path() / "missing").string();
  ScopedEnv env("MANIBENCH_PLUGIN_PATH",
                dir_a.string() + ":" + missing + "::" + dir_b.string());

  const std::vector<std::string> search = PluginRegistry::calcDefaultSearchPath();
  auto indexOf = [&](const fs::path& dir) -> std::ptrdiff_t {
    for (std::size_t i = 0; i < search.size(); ++i) {
      std::error_code ec;
      if (fs::equivalent(search[i], dir, ec)) return static_cast<std::ptrdiff_t>(i);
    }
    return -1;
  };
  const std::ptrdiff_t a = indexOf(dir_a), b = indexOf(dir_b);
  ASSERT_GE(a, 0) << joined(search);
  ASSERT_GE(b, 0) << joined(search);
  EXPECT_LT(a, b) << joined(search);
  for (const std::string& dir : search) EXPECT_TRUE(fs::is_directory(dir)) << dir;
  EXPECT_EQ(std::count(search.begin(), search.end(), search[a]), 1);
  if (fs::is_directory(kBuildPluginDir)) {
    const std::ptrdiff_t build = indexOf(kBuildPluginDir);
    ASSERT_GE(build, 0) << joined(search);
    EXPECT_LT(b, build) << joined(search);
  }

  // Same file name in both: loaded once, from the first directory, and the
  // second copy is shadowed silently (no duplicate-name failure).
  PluginRegistry registry;
  registry.loadDirectories({dir_a.string(), dir_b.string()});
  EXPECT_TRUE(registry.getFailures().empty()) << describeFailures(registry);
  ASSERT_EQ(registry.getLibraries().size(), 1u);
  EXPECT_TRUE(fs::equivalent(registry.getLibraries()[0].path, dir_a / file))
      << registry.getLibraries()[0].path;
  EXPECT_EQ(registry.getNames(PluginKind::Policy),
            std::vector<std::string>{"newer_minor_policy"});
  expectZeroPolicyWorks(registry.getPolicy("newer_minor_policy"));

  // The whole default search path: the environment's directory wins too.
  PluginRegistry from_search_path;
  from_search_path.loadSearchPath();
  const PluginEntry* entry = from_search_path.findEntry(PluginKind::Policy, "newer_minor_policy");
  ASSERT_NE(entry, nullptr) << describeFailures(from_search_path);
  EXPECT_TRUE(fs::equivalent(from_search_path.getLibraries()[entry->library].path, dir_a / file));
  for (const LoadFailure& f : from_search_path.getFailures())
    EXPECT_FALSE(contains(f.path, file)) << f.path << ": " << f.message;
}

// ABI 1.4's optional policy field: an older policy loads and names no
// controller; an SDK policy names the one it was registered for.
TEST(PluginRegistry, PolicyControllerIsOptional) {
  static_assert(MB_ABI_MINOR >= 4, "mb_policy_descriptor.controller is ABI 1.4");
  PluginRegistry registry;
  ASSERT_NO_THROW(registry.loadLibrary(fixturePath("fixture_pre_controller_policy")));
  EXPECT_TRUE(registry.getFailures().empty()) << describeFailures(registry);
  const mb_policy_descriptor& old_policy = registry.getPolicy("pre_controller_policy");
  EXPECT_LT(old_policy.header.struct_size, sizeof(mb_policy_descriptor));
  EXPECT_EQ(manibench::getPolicyController(old_policy), "");
  expectZeroPolicyWorks(old_policy);

  PluginRegistry tree;
  tree.loadDirectories({kBuildPluginDir});
  EXPECT_EQ(manibench::getPolicyController(tree.getPolicy("open_cabinet_expert")), "mobile_panda_ee");
  EXPECT_EQ(manibench::getPolicyController(tree.getPolicy("zero")), "");
  EXPECT_EQ(tree.getPolicy("zero").header.struct_size, sizeof(mb_policy_descriptor));
}

TEST(PluginRegistry, SameLibraryIsLoadedOnce) {
  TempDir temp;
  const std::string path = fixturePath("fixture_newer_minor");
  const fs::path link = temp.path() / "link_to_newer_minor.so";
  fs::create_symlink(path, link);

  PluginRegistry registry;
  ASSERT_NO_THROW(registry.loadLibrary(path));
  EXPECT_NO_THROW(registry.loadLibrary(path));
  EXPECT_NO_THROW(registry.loadLibrary(kFixtureDir + "/./" + fixtureFile("fixture_newer_minor")));
  EXPECT_NO_THROW(registry.loadLibrary(link.string()));
  EXPECT_NO_THROW(registry.loadDirectories({kFixtureDir, kFixtureDir}));

  std::size_t copies = 0;
  for (const auto& library : registry.getLibraries())
    if (library.name == "fixture_newer_minor") ++copies;
  EXPECT_EQ(copies, 1u);
  const auto names = registry.getNames(PluginKind::Policy);
  EXPECT_EQ(std::count(names.begin(), names.end(), "newer_minor_policy"), 1);
}

TEST(PluginRegistry, RelativePathLoads) {
  const fs::path old_cwd = fs::current_path();
  fs::current_path(kFixtureDir);
  PluginRegistry registry;
  EXPECT_NO_THROW(registry.loadLibrary(fixtureFile("fixture_newer_minor")));
  fs::current_path(old_cwd);
  ASSERT_EQ(registry.getLibraries().size(), 1u);
  EXPECT_TRUE(fs::path(registry.getLibraries()[0].path).is_absolute());
}

// ---- exceptions never cross the ABI --------------------------------------

class ThrowingFixture : public ::testing::Test {
 protected:
  void SetUp() override { registry.loadLibrary(fixturePath("fixture_throwing_create")); }
  PluginRegistry registry;
};

TEST_F(ThrowingFixture, TaskCreateReportsTheExceptionAsStatus) {
  const mb_task_descriptor& task = registry.getTask("Throwing-v0");
  ErrorBuffer e;
  mb_task* handle = reinterpret_cast<mb_task*>(&e);  // must be reset to null
  EXPECT_NE(task.create("", &handle, &e.err), MB_OK);
  EXPECT_EQ(handle, nullptr);
  EXPECT_TRUE(contains(e.text, "fixture: create failed on purpose"));

  // A short buffer gets a truncated, NUL-terminated message and nothing past
  // its capacity; no buffer at all is fine too.
  char small[16];
  std::memset(small, '#', sizeof(small));
  mb_error short_err{small, 8};
  EXPECT_NE(task.create(nullptr, &handle, &short_err), MB_OK);
  EXPECT_STREQ(small, "fixture");
  EXPECT_EQ(small[8], '#');
  EXPECT_NE(task.create("", &handle, nullptr), MB_OK);
}

TEST_F(ThrowingFixture, ControllerCreateReportsTheExceptionAsStatus) {
  const mb_controller_descriptor& controller = registry.getController("throwing_controller");
  mb_controller_context context{};
  context.struct_size = sizeof(context);
  context.articulation = 0;
  context.control_frequency = 100;
  ErrorBuffer e;
  mb_controller* handle = nullptr;
  EXPECT_NE(controller.create("", &context, &handle, &e.err), MB_OK);
  EXPECT_EQ(handle, nullptr);
  EXPECT_TRUE(contains(e.text, "fixture: controller create failed on purpose"));
}

TEST_F(ThrowingFixture, PolicyActReportsTheExceptionAsStatus) {
  const mb_policy_descriptor& policy = registry.getPolicy("throwing_policy");
  const mb_policy_context context = makePolicyContext("Throwing-v0", 1, 1);
  ErrorBuffer e;
  mb_policy* handle = nullptr;
  ASSERT_EQ(policy.create("", &context, &handle, &e.err), MB_OK) << e.text;
  ASSERT_NE(handle, nullptr);

  const double state[1] = {0};
  const mb_observation observation = makeObservation(state, 1);
  double action[1] = {0};
  EXPECT_EQ(policy.act(handle, &observation, action, 1, &e.err), MB_ERROR);
  EXPECT_TRUE(contains(e.text, "fixture: act failed on purpose"));
  // The policy survives its failure: the next call fails the same way.
  std::strcpy(e.text, "untouched");
  EXPECT_EQ(policy.act(handle, &observation, action, 1, &e.err), MB_ERROR);
  EXPECT_TRUE(contains(e.text, "act failed on purpose"));
  policy.destroy(handle);
}

TEST(PluginKindNames, AreLowerCase) {
  EXPECT_STREQ(manibench::toString(PluginKind::Task), "task");
  EXPECT_STREQ(manibench::toString(PluginKind::Controller), "controller");
  EXPECT_STREQ(manibench::toString(PluginKind::Policy), "policy");
}

}  // namespace
