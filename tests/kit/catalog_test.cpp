// The kit's object ids and catalog (manibench/kit/object_ids.hpp,
// catalog.hpp): numbered splits, models made once, a PartNet folder's
// unusable objects skipped with one warning each, and folders of several
// categories split by category.
#include <manibench/kit/catalog.hpp>

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "test_support.hpp"

namespace {

namespace kit = manibench::kit;
using manibench::testing::catchMessage;
using manibench::testing::expectMentions;

TEST(NumberedIds, SplitsAreRangesOfPlainNumbers) {
  const kit::NumberedIds ids{{3000, 3}, {3100, 2}};
  EXPECT_EQ(ids.list("train"), (std::vector<std::string>{"3000", "3001", "3002"}));
  EXPECT_EQ(ids.list("test"), (std::vector<std::string>{"3100", "3101"}));
  EXPECT_EQ(ids.classify("3001"), std::optional<bool>(false));
  EXPECT_EQ(ids.classify("3101"), std::optional<bool>(true));
  for (const char* bad : {"3003", "3102", "03001", "3001 ", "+3001", "", "abc", "99999999999"})
    EXPECT_EQ(ids.classify(bad), std::nullopt) << bad;
  EXPECT_EQ(ids.describe(), "train 3000-3002, test 3100-3101");
  expectMentions(catchMessage<kit::Error>([&] { ids.list("val"); }), {"unknown split 'val'", "train or test"});
}

struct Model {
  std::string id;
  bool usable = true;
  int finished = 0;
};

kit::ObjectCatalog<Model>::Source makeSource(int& made) {
  return {[](const std::string& split) { return kit::NumberedIds{{1, 2}, {5, 1}}.list(split); },
          [&made](const std::string& id) {
            ++made;
            return Model{id};
          },
          [&made](const std::string& folder, const std::string& id) {
            ++made;
            if (!std::filesystem::exists(folder + "/" + id + "/semantics.txt"))
              throw kit::Error("cannot read " + folder + "/" + id + "/semantics.txt");
            return Model{id, id != "100002"};
          },
          [](const Model& m) { return m.usable ? std::string() : std::string("no handle"); },
          [](Model& m) { ++m.finished; },
          [](const Model& m) { return m.id == "100001" ? std::vector<std::string>{"its lid: no handle"} : std::vector<std::string>{}; }};
}

TEST(ObjectCatalog, GeneratedModelsAreMadeOnceAndFinished) {
  int made = 0;
  const kit::ObjectCatalog<Model> catalog("Test", "thing", "", makeSource(made));
  EXPECT_FALSE(catalog.isPartNet());
  EXPECT_EQ(catalog.list("train"), (std::vector<std::string>{"1", "2"}));
  EXPECT_EQ(made, 0) << "listing a generator's split makes nothing";
  const auto a = catalog.get("2");
  EXPECT_EQ(catalog.get("2"), a);
  EXPECT_EQ(made, 1);
  EXPECT_EQ(a->finished, 1);
}

// One unreadable object and one the family refuses: both skipped, each
// named once per process with its folder and the reason; the rest listed,
// and what the family leaves out of them named once too.
TEST(ObjectCatalog, UnusablePartNetObjectsAreSkippedWithOneWarningEach) {
  const std::filesystem::path dir = ::testing::TempDir() + "catalog_" + std::to_string(::getpid());
  std::filesystem::remove_all(dir);
  std::filesystem::copy(std::string(MANIBENCH_TEST_SOURCE_DIR) + "/tests/fixtures/partnet_mini", dir,
                        std::filesystem::copy_options::recursive);
  std::filesystem::remove(dir / "test.txt");
  std::filesystem::create_directories(dir / "100003");
  std::ofstream(dir / "100003" / "mobility.urdf") << "<robot name=\"broken\">\n";
  int made = 0;
  const kit::ObjectCatalog<Model> catalog("Test", "thing", dir.string(), makeSource(made));
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(catalog.list("train"), std::vector<std::string>{"100001"});
  EXPECT_EQ(catalog.list("train"), std::vector<std::string>{"100001"});
  const std::string warnings = ::testing::internal::GetCapturedStderr();
  expectMentions(warnings, {"manibench: warning: Test: skipping PartNet thing 100003 (" + (dir / "100003").string() +
                                "): cannot read",
                            "skipping PartNet thing 100002 (" + (dir / "100002").string() + "): no handle"});
  EXPECT_EQ(warnings.find("100003"), warnings.rfind("100003 (")) << "warned once: " << warnings;
  const std::string note = "manibench: warning: Test: PartNet thing 100001 (" + (dir / "100001").string() +
                           "): leaving out its lid: no handle\n";
  EXPECT_NE(warnings.find(note), std::string::npos) << warnings;
  EXPECT_EQ(warnings.find(note), warnings.rfind(note)) << "noted once: " << warnings;
  EXPECT_EQ(warnings.find("skipping PartNet thing 100001"), std::string::npos) << warnings;
  // The skipped object itself still says why.
  expectMentions(catchMessage<kit::Error>([&] { catalog.get("100003"); }), {"cannot read"});
  std::filesystem::remove_all(dir);
}

// Two category folders (the mini fixture's objects, one in each): by
// category the test split is the named folder's objects, train the
// other's; without, each folder's test.txt (none here: all train). Each
// object is loaded from its own folder.
TEST(ObjectCatalog, FoldersOfSeveralCategoriesSplitByCategory) {
  const std::filesystem::path dir = ::testing::TempDir() + "categories_" + std::to_string(::getpid());
  std::filesystem::remove_all(dir);
  const std::string mini = std::string(MANIBENCH_TEST_SOURCE_DIR) + "/tests/fixtures/partnet_mini";
  for (const auto& [category, id] : {std::pair{"Cupboard", "100001"}, std::pair{"Microwave", "100002"}}) {
    std::filesystem::create_directories(dir / category);
    std::filesystem::copy(mini + "/" + id, dir / category / id, std::filesystem::copy_options::recursive);
  }
  const std::vector<std::string> folders = {(dir / "Cupboard").string(), (dir / "Microwave").string() + "/"};
  const kit::PartNetFolders by_category(folders, {"Microwave"});
  EXPECT_EQ(by_category.list("test"), std::vector<std::string>{"100002"});
  EXPECT_EQ(by_category.list("train"), std::vector<std::string>{"100001"});
  EXPECT_EQ(kit::PartNetFolders::getCategory(folders[1]), "Microwave");
  EXPECT_EQ(kit::PartNetFolders(folders, {}).list("train"), (std::vector<std::string>{"100001", "100002"}));
  EXPECT_TRUE(kit::PartNetFolders(folders, {}).list("test").empty());
  int made = 0;
  const kit::ObjectCatalog<Model> catalog("Test", "thing", by_category, makeSource(made));
  ::testing::internal::CaptureStderr();
  EXPECT_TRUE(catalog.list("test").empty()) << "the fixture's 100002 has no handle";
  EXPECT_EQ(catalog.list("train"), std::vector<std::string>{"100001"});
  expectMentions(::testing::internal::GetCapturedStderr(),
                 {"skipping PartNet thing 100002 (" + (dir / "Microwave" / "100002").string() + "): no handle"});
  // Read from the task's keys, as a list and as one name.
  const std::string yaml =
      "partnet_dir: [" + folders[0] + ", " + folders[1] + "]\npartnet_test_categories: Microwave\n";
  const kit::Config config(yaml.c_str());
  EXPECT_EQ(kit::readPartNetFolders(config, "Test").list("test"), std::vector<std::string>{"100002"});
  expectMentions(catchMessage<kit::Error>([&] {
                   const std::string one = "partnet_dir: " + folders[0] + "\npartnet_test_categories: [Oven]";
                   kit::readPartNetFolders(kit::Config(one.c_str()), "Test");
                 }),
                 {"Test: task.partnet_test_categories", "'Oven' is none of the folders' (Cupboard)"});
  expectMentions(catchMessage<kit::Error>(
                     [&] { kit::readPartNetFolders(kit::Config("partnet_test_categories: [Oven]"), "Test"); }),
                 {"needs task.partnet_dir"});
  // An id in two folders is refused, naming both.
  std::filesystem::copy(mini + "/100001", dir / "Microwave" / "100001", std::filesystem::copy_options::recursive);
  expectMentions(catchMessage<kit::Error>([&] { by_category.list("train"); }),
                 {"object 100001 is in two folders", (dir / "Cupboard").string()});
  std::filesystem::remove_all(dir);
}

TEST(ObjectCatalog, PartNetDirMustBeAFolder) {
  const kit::Config none("{}");
  EXPECT_EQ(kit::readPartNetDir(none, "Test"), "");
  const kit::Config bad("partnet_dir: /no/such/folder");
  expectMentions(catchMessage<kit::Error>([&] { kit::readPartNetDir(bad, "Test"); }),
                 {"Test: task.partnet_dir '/no/such/folder' is not a folder"});
}

}  // namespace
