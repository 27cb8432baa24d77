// manibench eval --verify DIR: checks an evaluation report against its
// certificate and re-runs its episodes (docs/evaluation.md, "Verifying a
// report"). The first difference is the verdict, in this order: the build,
// a plugin's or policy file's hash, an object's file, the configuration,
// the report's files against its journal, then the episodes themselves.
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <manibench/evaluation.hpp>
#include <manibench/sha256.hpp>
#include <nlohmann/json.hpp>
#include <sstream>

#include "eval_setup.hpp"

namespace manibench::cli {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

// A verdict: what differs first.
class Mismatch : public Error {
 public:
  using Error::Error;
};

std::string readFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw EvaluationError("cannot read '" + path.string() + "': " + std::strerror(errno));
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The first line where `a` (the report's) and `b` differ: "line 3: 'x' in the
// report, 'y' ..."; "" when equal.
std::string findLineDifference(const std::string& a, const std::string& b, const std::string& other) {
  std::istringstream x(a), y(b);
  std::string p, q;
  for (std::size_t line = 1;; ++line) {
    const bool more_x = bool(std::getline(x, p)), more_y = bool(std::getline(y, q));
    if (!more_x && !more_y) return "";
    if (!more_x) p = "(nothing)";
    if (!more_y) q = "(nothing)";
    if (p != q || !more_x || !more_y)
      return "line " + std::to_string(line) + ": '" + p + "' in the report, '" + q + "' " + other;
  }
}

std::string withoutTimingLine(const std::string& json) {
  std::istringstream in(json);
  std::string line, out;
  while (std::getline(in, line))
    if (line.rfind("  \"timing\":", 0) != 0) out += line + "\n";
  return out;
}

void checkBuild(const Json& certificate) {
  const std::string version = certificate.value("manibench_version", ""), build = certificate.value("build_id", "");
  if (version != getManibenchVersion() || build != getManibenchBuildId())
    throw Mismatch("build: the report was made by manibench " + version + " build " + build + "; this is " +
                   getManibenchVersion() + " build " + getManibenchBuildId() +
                   " (verify with the build that made it: its results are bit for bit that build's)");
}

// The plugins' libraries and the policy's files as they are now, against
// the certificate's.
std::size_t checkInputs(const Json& certificate, const std::vector<FileDigest>& now) {
  const Json& inputs = certificate.at("inputs");
  for (std::size_t i = 0; i < inputs.size() || i < now.size(); ++i) {
    if (i >= inputs.size() || i >= now.size()) {
      const FileDigest& d = i < now.size() ? now[i] : FileDigest{inputs[i].at("role"), inputs[i].at("name"),
                                                                 inputs[i].at("file"), ""};
      throw Mismatch(d.role + " '" + d.name + "' (" + d.path + "): " +
                     (i < now.size() ? "not in the report's certificate" : "in the report, not in this run"));
    }
    const Json& was = inputs[i];
    const FileDigest& is = now[i];
    if (was.at("role") != is.role || was.at("name") != is.name)
      throw Mismatch(std::string(was.at("role")) + " '" + std::string(was.at("name")) + "' in the report, " +
                     is.role + " '" + is.name + "' now");
    if (was.at("sha256") != is.sha256)
      throw Mismatch(is.role + " '" + is.name + "' (" + is.path + "): sha256 " + std::string(was.at("sha256")) +
                     " in the report, " + is.sha256 + " now (rebuilt or replaced)");
  }
  return now.size();
}

// Every object file the report's scenes read, hashed again (URDF texts
// that a task generates are checked by the episodes' re-run).
std::size_t checkObjectFiles(const Json& certificate) {
  std::size_t files = 0;
  for (const auto& [object, lines] : certificate.at("objects").items())
    for (const Json& entry : lines) {
      const std::string line = entry;
      const std::string digest = line.substr(0, 64), file = line.size() > 66 ? line.substr(66) : "";
      if (file.rfind("urdf text of articulation", 0) == 0) continue;
      std::string now;
      try {
        now = calcFileSha256(file);
      } catch (const std::exception& e) {
        throw Mismatch("object '" + object + "': " + e.what());
      }
      if (now != digest)
        throw Mismatch("object '" + object + "': file " + file + ": sha256 " + digest + " in the report, " + now +
                       " now");
      ++files;
    }
  return files;
}

void checkConfiguration(const Json& certificate, const std::string& now) {
  const std::string was = certificate.at("configuration").at("yaml");
  const std::string difference = findLineDifference(was, now, "now");
  if (!difference.empty()) throw Mismatch("configuration: " + difference);
}

// The report's files as its journal gives them: a file edited by hand
// differs here.
void checkReportFiles(const fs::path& dir, const EvaluationResult& journal_result) {
  const fs::path scratch = fs::temp_directory_path() / ("manibench-verify-files-" + std::to_string(getpid()));
  writeEvaluationFiles(scratch.string(), journal_result);
  for (const char* name : {"episodes.csv", "summary.csv", "summary.json", "certificate.json"}) {
    std::string was = readFile(dir / name), now = readFile(scratch / name);
    if (std::string(name) == "summary.json") {
      was = withoutTimingLine(was);
      now = withoutTimingLine(now);
    }
    const std::string difference = findLineDifference(was, now, "from the journal's episodes");
    if (!difference.empty()) {
      fs::remove_all(scratch);
      throw Mismatch(std::string(name) + ": " + difference + " (changed after the run)");
    }
  }
  fs::remove_all(scratch);
}

std::string describeEpisode(const EpisodeSpec& spec) {
  return "episode " + std::to_string(spec.index) + " (object " + spec.object_id + ", level " +
         std::to_string(spec.level) + ", seed " + std::to_string(spec.seed) + ")";
}

// The first field where a re-run differs from the report's record.
void compareRecords(const EpisodeRecord& was, const EpisodeRecord& is) {
  auto differ = [&](const std::string& field, const std::string& a, const std::string& b) {
    throw Mismatch(describeEpisode(was.spec) + ": " + field + " " + a + " in the report, " + b + " re-run");
  };
  auto text = [](double v) {
    std::ostringstream out;
    out.precision(17);
    out << v;
    return out.str();
  };
  if (was.steps != is.steps) differ("steps", std::to_string(was.steps), std::to_string(is.steps));
  if (std::memcmp(&was.total_reward, &is.total_reward, sizeof(double)) != 0)
    differ("return", text(was.total_reward), text(is.total_reward));
  if (was.success != is.success) differ("success", was.success ? "1" : "0", is.success ? "1" : "0");
  if (was.success_once != is.success_once)
    differ("success_once", was.success_once ? "1" : "0", is.success_once ? "1" : "0");
  for (std::size_t c = 0; c < was.flags.size() || c < is.flags.size(); ++c) {
    const int a = c < was.flags.size() ? was.flags[c] : -1, b = c < is.flags.size() ? is.flags[c] : -1;
    if (a != b) differ("condition " + std::to_string(c), std::to_string(a), std::to_string(b));
  }
  if (std::memcmp(&was.max_opened, &is.max_opened, sizeof(double)) != 0)
    differ("max_opened", text(was.max_opened), text(is.max_opened));
  if (was.failure != is.failure) differ("failure", "'" + was.failure + "'", "'" + is.failure + "'");
  if (was.failure_step != is.failure_step)
    differ("failure step", std::to_string(was.failure_step), std::to_string(is.failure_step));
  if (was.message != is.message) differ("message", "'" + was.message + "'", "'" + is.message + "'");
  if (was.sources != is.sources) {
    for (std::size_t i = 0; i < was.sources.size() || i < is.sources.size(); ++i) {
      const std::string a = i < was.sources.size() ? was.sources[i] : "(nothing)";
      const std::string b = i < is.sources.size() ? is.sources[i] : "(nothing)";
      if (a != b) differ("scene file", "'" + a + "'", "'" + b + "'");
    }
  }
}

// `count` episodes spread evenly over the list (all when 0 or more).
std::vector<std::size_t> chooseSample(std::size_t total, std::size_t count) {
  std::vector<std::size_t> chosen;
  if (count == 0 || count >= total) count = total;
  for (std::size_t i = 0; i < count; ++i) chosen.push_back(i * total / count);
  return chosen;
}

const char* const kVerifyUsage = R"(usage: manibench eval --verify DIR [--sample N] [--workers N] [--no-progress]

Checks the evaluation report in DIR (an `eval --out` folder) against its
certificate.json and runs its episodes again (all, or N spread over the
list): passes when each is the same bit for bit, else names what differs
first: the build, a plugin's or policy file's SHA-256, an object's file, the
configuration, a report file against the journal (edited by hand), an
episode. Exit status 0: verified; 1: it differs (or cannot be checked).
)";

}  // namespace

int verifyEvaluation(int argc, char** argv) {
  const Arguments args =
      parseArguments(argc, argv, 2, {"verify", "sample", "workers"}, {"no-progress"}, kVerifyUsage, {});
  if (args.help) {
    std::cout << kVerifyUsage;
    return 0;
  }
  if (!args.positional.empty() || valueOr(args, "verify", "").empty())
    throw UsageError("eval --verify takes a report folder and --sample, --workers only", kVerifyUsage);
  const fs::path dir = fs::absolute(args.options.at("verify"));
  const std::size_t sample = parseSeed(valueOr(args, "sample", "0"), kVerifyUsage, "--sample");
  const std::string workers = valueOr(args, "workers", "1");
  if (!fs::exists(dir / "certificate.json"))
    throw EvaluationError(dir.string() + " has no certificate.json (not an `eval --out` folder, or made before "
                                         "reports had certificates)");
  Json certificate;
  try {
    certificate = Json::parse(readFile(dir / "certificate.json"));
  } catch (const Json::exception& e) {
    throw EvaluationError((dir / "certificate.json").string() + ": not JSON (" + e.what() + ")");
  }
  const EvaluationJournal journal = readJournal((dir / kJournalFileName).string());
  if (journal.result.episodes.size() != journal.result.planned.size())
    throw EvaluationError(dir.string() + " holds " + std::to_string(journal.result.episodes.size()) + " of " +
                          std::to_string(journal.result.planned.size()) +
                          " episodes: complete it (eval --resume) before verifying");
  try {
    checkBuild(certificate);
    const std::string cwd = certificate.value("working_directory", "");
    if (!cwd.empty() && fs::is_directory(cwd)) fs::current_path(cwd);
    std::vector<std::string> words = {"manibench", "eval"};
    for (const Json& word : certificate.at("command")) words.push_back(word);
    words.push_back("--workers=" + workers);
    words.push_back("--no-progress");
    std::vector<char*> pointers;
    for (std::string& word : words) pointers.push_back(word.data());
    const std::unique_ptr<EvalSetup> setup = prepareEval(parseEvalArguments(int(pointers.size()), pointers.data(), 2));
    EvaluationOptions& options = setup->options;
    options.shard = journal.result.options.shard;
    options.shards = journal.result.options.shards;
    const std::size_t inputs = checkInputs(
        certificate, calcInputDigests(setup->registry, options, journal.result.task.controller));
    const std::size_t object_files = checkObjectFiles(certificate);
    checkConfiguration(certificate, options.configuration);
    checkReportFiles(dir, journal.result);

    // The episodes: the sampled ones run again, the others taken as the
    // journal has them (the resume path), each re-run compared.
    const std::vector<EpisodeRecord>& recorded = journal.result.episodes;
    std::vector<bool> chosen(recorded.size(), false);
    for (std::size_t i : chooseSample(recorded.size(), sample)) chosen[i] = true;
    for (std::size_t i = 0; i < recorded.size(); ++i)
      if (!chosen[i]) options.resumed.push_back(recorded[i]);
    options.resumed_header = journal.header;
    const fs::path scratch = fs::temp_directory_path() / ("manibench-verify-" + std::to_string(getpid()));
    fs::create_directories(scratch);
    options.journal_path = (scratch / kJournalFileName).string();
    // The resume path appends to the journal it resumes: a copy of the report's.
    fs::copy_file(dir / kJournalFileName, options.journal_path);
    std::map<std::size_t, EpisodeRecord> rerun;
    EvaluationHooks hooks;
    hooks.on_episode = [&rerun](EpisodeRecord& r) { rerun[r.spec.index] = r; };
    std::cout << "verify: build, " << inputs << " plugin and policy files, " << object_files
              << " object files, the configuration and the report's files match; re-running "
              << recorded.size() - options.resumed.size() << " of " << recorded.size() << " episodes\n"
              << std::flush;
    EvaluationResult result;
    try {
      result = evaluatePolicy(setup->registry, options, setup->run.factory, hooks);
    } catch (...) {
      fs::remove_all(scratch);
      throw;
    }
    fs::remove_all(scratch);
    if (result.interrupted) throw EvaluationError("the re-run stopped: " + result.stop_reason);
    for (const EpisodeRecord& was : recorded) {
      const auto is = rerun.find(was.spec.index);
      if (is != rerun.end()) compareRecords(was, is->second);
    }
    std::cout << "verified: " << rerun.size() << " episode(s) re-run, each the report's bit for bit\n";
    return 0;
  } catch (const Mismatch& e) {
    std::cout << "verify FAILED: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace manibench::cli
