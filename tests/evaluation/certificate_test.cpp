// An evaluation report's certificate and `eval --verify` (docs/evaluation.md,
// "Certificate", "Verifying a report"): SHA-256 against FIPS 180-4's
// examples, a report that verifies untouched and fails, naming the reason,
// after each kind of change (a rebuilt policy plugin, an object file, a
// configuration value, a success edited in episodes.csv, a journal and
// report forged to agree), and the same report whatever the workers and
// shards.
#include <gtest/gtest.h>

#include <manibench/evaluation.hpp>
#include <manibench/sha256.hpp>

#include <fstream>
#include <regex>

#include "eval_test_support.hpp"

namespace manibench {
namespace {

using testing::contains;
using testing::readFile;

const std::string kPluginDir = MANIBENCH_TEST_BUILD_PLUGIN_DIR;

void writeText(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
}

void replaceOnce(const fs::path& path, const std::string& from, const std::string& to) {
  std::string text = readFile(path);
  const std::size_t at = text.find(from);
  ASSERT_NE(at, std::string::npos) << from << " not in " << path;
  text.replace(at, from.size(), to);
  writeText(path, text);
}

// The "build_id" a report's JSON file gives ("" when none).
std::string findBuildId(const std::string& json) {
  std::smatch m;
  return std::regex_search(json, m, std::regex("\"build_id\": \"([0-9a-z:]+)\"")) ? m[1].str() : "";
}

testing::CommandResult verify(const fs::path& dir, const std::vector<std::string>& extra = {},
                              const std::vector<std::string>& environment = {}) {
  std::vector<std::string> arguments = {"eval", "--verify", dir.string()};
  arguments.insert(arguments.end(), extra.begin(), extra.end());
  return testing::runCli(arguments, environment);
}

TEST(Sha256, Fips180Examples) {
  EXPECT_EQ(calcSha256("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(calcSha256(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(calcSha256("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(calcSha256(std::string(1000000, 'a')),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  // Added piece by piece across block boundaries: the same digest.
  Sha256 pieces;
  const std::string text(1000, 'x');
  for (std::size_t at = 0; at < text.size(); at += 37) pieces.add(text.substr(at, 37));
  EXPECT_EQ(pieces.finish(), calcSha256(text));
  TempDir dir;
  writeText(dir / "f", "abc");
  EXPECT_EQ(calcFileSha256((dir / "f").string()), calcSha256("abc"));
  testing::expectMentions(testing::catchMessage<Error>([&] { calcFileSha256((dir / "missing").string()); }),
                          {(dir / "missing").string(), "cannot read"});
}

// A Reach evaluation of the `zero` policy from a copy of its library and a
// --config file, both in `dir`, so that the test can change them.
struct ReachReport {
  TempDir dir, out;
  std::vector<std::string> environment;
  ReachReport() {
    fs::copy_file(fs::path(kPluginDir) / "libmanibench_example_policies.so", dir / "libmanibench_example_policies.so");
    writeText(dir / "short.yaml", "episode:\n  max_steps: 20\n");
    environment = {"MANIBENCH_PLUGIN_PATH=" + dir.path().string()};
  }
  testing::CommandResult run(const std::vector<std::string>& extra = {}) {
    std::vector<std::string> arguments = {"Reach-v0", "--policy", "zero", "--objects", "8,10", "--levels", "0-1",
                                          "--config", (dir / "short.yaml").string()};
    arguments.insert(arguments.end(), extra.begin(), extra.end());
    return runEval(out, arguments, environment);
  }
};

TEST(Certificate, NamesWhatTheResultCameFrom) {
  ReachReport report;
  const auto r = report.run();
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  const std::string certificate = readFile(report.out / "certificate.json");
  const std::string policy_library = (report.dir / "libmanibench_example_policies.so").string();
  // The program's build, as summary.json says it too.
  EXPECT_EQ(findBuildId(certificate).size(), 40u) << certificate;
  EXPECT_EQ(findBuildId(readFile(report.out / "summary.json")), findBuildId(certificate));
  for (const std::string& part :
       {std::string("\"role\": \"task\""),
        std::string("\"role\": \"controller\""), "\"file\": \"" + policy_library + "\"",
        "\"sha256\": \"" + calcFileSha256(policy_library) + "\"", std::string("max_steps: 20"),
        std::string("urdf text of articulation 'arm'"),
        "\"episodes.csv\": \"" + calcSha256(readFile(report.out / "episodes.csv")) + "\"",
        "\"summary.csv\": \"" + calcSha256(readFile(report.out / "summary.csv")) + "\""})
    EXPECT_TRUE(contains(certificate, part)) << part << "\n" << certificate;
}

TEST(Certificate, VerifyPassesUntouchedAndNamesEachChange) {
  ReachReport report;
  ASSERT_EQ(report.run().exit_code, 0);
  const fs::path out = report.out.path();
  auto check = [&](const std::vector<std::string>& extra) { return verify(out, extra, report.environment); };
  auto r = check({});
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_TRUE(contains(r.out, "verified: 4 episode(s) re-run")) << r.out;
  r = check({"--sample", "2", "--workers", "2"});
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_TRUE(contains(r.out, "re-running 2 of 4 episodes")) << r.out;

  // A success edited in episodes.csv (the third line: object 8, level 1).
  const std::string episodes = readFile(out / "episodes.csv");
  std::string edited = episodes;
  const std::size_t line = edited.find("\n1,8,1,");
  ASSERT_NE(line, std::string::npos) << episodes;
  std::size_t field = line + 1;
  for (int comma = 0; comma < 6; ++comma) field = edited.find(',', field) + 1;  // the success column
  edited[field] = edited[field] == '1' ? '0' : '1';
  writeText(out / "episodes.csv", edited);
  r = check({});
  EXPECT_EQ(r.exit_code, 1) << r.out;
  testing::expectMentions(r.out, {"verify FAILED: episodes.csv: line 3", "changed after the run"});
  writeText(out / "episodes.csv", episodes);

  // A configuration value changed since.
  writeText(report.dir / "short.yaml", "episode:\n  max_steps: 21\n");
  r = check({});
  EXPECT_EQ(r.exit_code, 1) << r.out;
  testing::expectMentions(r.out, {"verify FAILED: configuration: line", "max_steps: 20", "max_steps: 21"});
  writeText(report.dir / "short.yaml", "episode:\n  max_steps: 20\n");

  // The policy plugin rebuilt (here: one byte more).
  const fs::path library = report.dir / "libmanibench_example_policies.so";
  const std::string bytes = readFile(library);
  writeText(library, bytes + "\n");
  r = check({});
  EXPECT_EQ(r.exit_code, 1) << r.out;
  testing::expectMentions(r.out, {"verify FAILED: policy 'zero'", library.string(), "rebuilt or replaced"});
  writeText(library, bytes);
  EXPECT_EQ(check({"--sample", "1"}).exit_code, 0);
}

// A --policy-config file and the files it names (torch_policy's
// checkpoint: PATH, here a file beside it) are the policy's own files.
TEST(Certificate, PolicyConfigurationAndTheFilesItNamesAreHashed) {
  TempDir dir, out;
  writeText(dir / "policy.yaml", "weights: weights.bin\n");
  writeText(dir / "weights.bin", "0123");
  const auto r = runEval(out, {"Reach-v0", "--policy", "zero", "--policy-config", (dir / "policy.yaml").string(),
                               "--objects", "8", "--levels", "0", "--set", "episode.max_steps=5"});
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  const std::string certificate = readFile(out / "certificate.json");
  const std::string weights = (dir / "weights.bin").string();
  EXPECT_TRUE(contains(certificate, "\"file\": \"" + weights + "\",\n      \"sha256\": \"" + calcSha256("0123")))
      << certificate;
  EXPECT_EQ(verify(out.path()).exit_code, 0);
  writeText(dir / "weights.bin", "0124");
  const auto v = verify(out.path());
  EXPECT_EQ(v.exit_code, 1) << v.out;
  testing::expectMentions(v.out, {"verify FAILED: policy file", weights, calcSha256("0123") + " in the report"});
}

// A journal and report forged to agree (one episode's success flipped, the
// files written again from the forged journal): only the re-run shows it.
TEST(Certificate, VerifyRerunsTheEpisodesOfAForgedReport) {
  ReachReport report;
  ASSERT_EQ(report.run().exit_code, 0);
  const fs::path out = report.out.path();
  const std::string build = getManibenchBuildId();  // this test's, not the CLI's
  const std::string report_build = findBuildId(readFile(out / "certificate.json"));
  ASSERT_FALSE(report_build.empty());
  // Episode 1 (object 8, level 1): its journal line says success now.
  const fs::path journal = out / kJournalFileName;
  std::string text = readFile(journal);
  const std::size_t at = text.find("{\"episode\":1,");
  ASSERT_NE(at, std::string::npos) << text;
  const std::string honest = "\"success\":false,\"flags\":[0,1,0]";
  const std::size_t success = text.find(honest, at);
  ASSERT_NE(success, std::string::npos) << text.substr(at, 300);
  text.replace(success, honest.size(), "\"success\":true,\"flags\":[1,1,1]");
  writeText(journal, text);
  writeEvaluationFiles(out.string(), readJournal(journal.string()).result);
  // The files as the run's program would write them (the build is this test's here).
  for (const char* name : {"summary.json", "certificate.json"}) {
    std::string file = readFile(out / name);
    for (std::size_t p; (p = file.find(build)) != std::string::npos;) file.replace(p, build.size(), report_build);
    writeText(out / name, file);
  }
  const auto r = verify(out, {}, report.environment);
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  testing::expectMentions(r.out, {"verify FAILED: episode 1 (object 8, level 1, seed", "success 1 in the report, 0 re-run"});
}

// A procedural bucket's meshes, made once into the cache folder: a mesh
// changed since the run is named.
TEST(Certificate, VerifyNamesAChangedObjectFile) {
  TempDir cache, out;
  const std::vector<std::string> environment = {"MANIBENCH_CACHE_DIR=" + cache.path().string()};
  const auto r = runEval(out, {"MoveBucket-v0", "--policy", "zero", "--objects", "3100", "--levels", "0", "--set",
                               "episode.max_steps=3"},
                         environment);
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  const std::string certificate = readFile(out / "certificate.json");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(certificate, m, std::regex("  (/[^\"]*/buckets/[^\"]*piece_00\\.obj)\"")))
      << certificate;
  const std::string mesh = m[1];
  EXPECT_TRUE(contains(certificate, calcFileSha256(mesh) + "  " + mesh));
  EXPECT_EQ(verify(out.path(), {}, environment).exit_code, 0);
  writeText(mesh, readFile(mesh) + "# edited\n");
  const auto v = verify(out.path(), {}, environment);
  EXPECT_EQ(v.exit_code, 1) << v.out;
  testing::expectMentions(v.out, {"verify FAILED: object '3100': file " + mesh, "in the report"});
}

// The same report, certificate included, for 1 and 2 workers and for two
// shards merged; the merged one verifies.
TEST(Certificate, ReportIsIndependentOfWorkersAndShards) {
  TempDir one, two, first, second, merged;
  const std::vector<std::string> common = {"Reach-v0", "--policy", "random", "--objects", "8,11", "--levels", "0-2",
                                           "--set", "episode.max_steps=15"};
  auto with = [&](const std::vector<std::string>& extra) { return joinArguments(common, extra); };
  ASSERT_EQ(runEval(one, with({"--workers", "1"})).exit_code, 0);
  ASSERT_EQ(runEval(two, with({"--workers", "2"})).exit_code, 0);
  ASSERT_EQ(runEval(first, with({"--shard", "1/2"})).exit_code, 0);
  ASSERT_EQ(runEval(second, with({"--shard", "2/2", "--workers", "2"})).exit_code, 0);
  const auto m = testing::runCli({"eval", "merge", first.path().string(), second.path().string(), "--out",
                                  merged.path().string()});
  ASSERT_EQ(m.exit_code, 0) << m.err << m.out;
  for (const TempDir* d : {&two, &merged}) {
    for (const char* name : {"episodes.csv", "summary.csv", "certificate.json"})
      EXPECT_EQ(readFile(*d / name), readFile(one / name)) << name;
    EXPECT_EQ(withoutTiming(readFile(*d / "summary.json")), withoutTiming(readFile(one / "summary.json")));
  }
  const auto v = verify(merged.path(), {"--sample", "3"});
  EXPECT_EQ(v.exit_code, 0) << v.out << v.err;
}

}  // namespace
}  // namespace manibench
