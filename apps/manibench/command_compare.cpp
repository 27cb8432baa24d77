// manibench compare A B: two evaluation reports of the same episodes (task,
// split, seed, objects, levels), compared pair by pair: each (object,
// level, seed) episode is the same episode under both policies, so the
// difference of their success rates is a paired one (docs/evaluation.md,
// "Comparing two policies").
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <manibench/evaluation.hpp>
#include <manibench/statistics.hpp>
#include <sstream>

#include "cli.hpp"

namespace manibench::cli {

namespace {

const char* const kCompareUsage = R"(usage: manibench compare A B [--margin M]

Compares two `manibench eval --out` folders of the same task, split, seed,
objects and levels (refused otherwise, naming what differs): per object and
overall, the success rates, their paired difference A - B with a 95 %
bootstrap interval (over episode pairs for an object; over objects for the
whole split), the discordant pairs and McNemar's exact two-sided p-value;
then how many episodes per object a paired run needs to tell a difference
of --margin (default 0.05) from none (5 % test, 80 % power).
)";

// The first difference of the two runs' episode lists, "" when none.
std::string findListDifference(const EvaluationResult& a, const EvaluationResult& b) {
  const EvaluationOptions &x = a.options, &y = b.options;
  auto list = [](const auto& items) {
    std::ostringstream out;
    for (std::size_t i = 0; i < items.size(); ++i) out << (i ? "," : "") << items[i];
    return out.str();
  };
  if (x.task != y.task) return "task: '" + x.task + "' in A, '" + y.task + "' in B";
  if (x.split != y.split) return "split: " + x.split + " in A, " + y.split + " in B";
  if (x.seed != y.seed) return "seed: " + std::to_string(x.seed) + " in A, " + std::to_string(y.seed) + " in B";
  if (x.objects != y.objects) return "objects: " + list(x.objects) + " in A, " + list(y.objects) + " in B";
  if (x.levels != y.levels) return "levels: " + list(x.levels) + " in A, " + list(y.levels) + " in B";
  if (x.shards != y.shards || x.shard != y.shard) return "shard: the two hold different shares of the list";
  return "";
}

std::string formatSigned(double value) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(3) << std::showpos << value;
  return out.str();
}

void printRow(const PairedDifference& d, std::size_t width) {
  const PairedCounts& c = d.counts;
  std::ostringstream interval;
  interval << "[" << formatSigned(d.low) << ", " << formatSigned(d.high) << "]";
  std::ostringstream p;
  p << std::setprecision(3) << d.p_value;
  std::cout << std::left << std::setw(int(width)) << c.object << std::right << std::setw(7) << c.pairs
            << std::fixed << std::setprecision(3) << std::setw(8) << (c.pairs ? double(c.successes_a) / c.pairs : 0)
            << std::setw(8) << (c.pairs ? double(c.successes_b) / c.pairs : 0) << std::setw(9)
            << formatSigned(d.difference) << std::setw(18) << interval.str() << std::setw(8) << c.only_a
            << std::setw(8) << c.only_b << std::setw(9) << p.str() << "\n";
  std::cout.unsetf(std::ios::fixed);
}

}  // namespace

int commandCompare(int argc, char** argv) {
  const Arguments args = parseArguments(argc, argv, 2, {"margin"}, {}, kCompareUsage, {});
  if (args.help) {
    std::cout << kCompareUsage;
    return 0;
  }
  if (args.positional.size() != 2) throw UsageError("compare takes two report folders, A and B", kCompareUsage);
  double margin = 0.05;
  if (args.options.count("margin")) {
    const std::string& text = args.options.at("margin");
    char* end = nullptr;
    margin = std::strtod(text.c_str(), &end);
    if (text.empty() || *end != '\0' || !(margin > 0 && margin <= 1))
      throw UsageError("--margin needs a number in (0, 1], got '" + text + "'", kCompareUsage);
  }
  const EvaluationJournal a = readJournal((std::filesystem::path(args.positional[0]) / kJournalFileName).string());
  const EvaluationJournal b = readJournal((std::filesystem::path(args.positional[1]) / kJournalFileName).string());
  const std::string difference = findListDifference(a.result, b.result);
  if (!difference.empty())
    throw EvaluationError("compare: " + args.positional[0] + " and " + args.positional[1] +
                          " are not of the same episodes (" + difference + ")");
  for (const EvaluationJournal* j : {&a, &b})
    if (j->result.episodes.size() != j->result.planned.size())
      throw EvaluationError("compare: " + j->path + " holds " + std::to_string(j->result.episodes.size()) + " of " +
                            std::to_string(j->result.planned.size()) + " episodes (complete it with eval --resume)");
  // Episode i of A and of B are the same (object, level, seed): both lists
  // follow from the same options, and the journals hold them by index.
  std::vector<PairedCounts> objects;
  for (std::size_t i = 0; i < a.result.episodes.size(); ++i) {
    const EpisodeRecord &x = a.result.episodes[i], &y = b.result.episodes[i];
    if (objects.empty() || objects.back().object != x.spec.object_id) objects.push_back({x.spec.object_id});
    PairedCounts& c = objects.back();
    ++c.pairs;
    c.successes_a += x.success;
    c.successes_b += y.success;
    c.only_a += x.success && !y.success;
    c.only_b += y.success && !x.success;
  }
  PairedDifference overall;
  const std::vector<PairedDifference> rows = comparePaired(objects, overall);
  std::cout << "A: " << a.result.options.policy << " (" << args.positional[0] << ")\nB: " << b.result.options.policy
            << " (" << args.positional[1] << ")\n" << a.result.options.task << ", " << a.result.options.split
            << " split, seed " << a.result.options.seed << ", " << a.result.options.levels.size()
            << " level(s) per object\n\n";
  std::size_t width = 8;
  for (const PairedCounts& c : objects) width = std::max(width, c.object.size() + 2);
  std::cout << std::left << std::setw(int(width)) << "object" << std::right << std::setw(7) << "pairs"
            << std::setw(8) << "A" << std::setw(8) << "B" << std::setw(9) << "A - B" << std::setw(18)
            << "95% interval" << std::setw(8) << "only A" << std::setw(8) << "only B" << std::setw(9) << "p"
            << "\n";
  for (const PairedDifference& d : rows) printRow(d, width);
  std::cout << std::string(width + 75, '-') << "\n";
  printRow(overall, width);
  const PairedCounts& all = overall.counts;
  const double discordance = all.pairs ? double(all.only_a + all.only_b) / all.pairs : 0;
  const uint64_t pairs = calcPairsNeeded(discordance, margin);
  const uint64_t per_object = (pairs + objects.size() - 1) / objects.size();
  std::cout << "\nintervals: bootstrap (" << kBootstrapResamples << " resamples); p: McNemar's exact test on the "
            << all.only_a + all.only_b << " discordant pairs\n"
            << "to tell a difference of " << margin << " from none (5 % two-sided, 80 % power) at this discordance ("
            << std::setprecision(3) << discordance << "): " << pairs << " episode pairs, " << per_object
            << " episodes per object over " << objects.size() << " objects\n";
  return 0;
}

}  // namespace manibench::cli
