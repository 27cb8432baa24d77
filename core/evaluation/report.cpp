// Aggregation of an evaluation's episodes and its outputs: the terminal
// table, summary.csv, episodes.csv and summary.json.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iterator>
#include <manibench/evaluation.hpp>
#include <manibench/statistics.hpp>
#include <map>
#include <ostream>
#include <sstream>

namespace manibench {
namespace {

// Numbers are printed the same way in every file, so that they can be
// compared as text: rates and means with 6 significant digits, returns
// with 9.
std::string formatNumber(double value, int digits) {
  if (!std::isfinite(value)) return std::isnan(value) ? "nan" : (value > 0 ? "inf" : "-inf");
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.*g", digits, value);
  return buffer;
}
std::string formatRate(double value) { return formatNumber(value, 6); }
std::string formatReturn(double value) { return formatNumber(value, 9); }

std::string escapeCsv(const std::string& field) {
  if (field.find_first_of(",\"\n\r") == std::string::npos) return field;
  std::string out = "\"";
  for (char c : field) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

std::string escapeJson(const std::string& text) {
  std::string out = "\"";
  for (unsigned char c : text) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\r':
        out += "\\r";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (c < 0x20) {
          char buffer[8];
          std::snprintf(buffer, sizeof(buffer), "\\u%04x", c);
          out += buffer;
        } else {
          out += static_cast<char>(c);
        }
    }
  }
  return out + "\"";
}

// A JSON number; JSON has no NaN or infinity, so those become null.
std::string jsonNumber(double value, int digits) {
  return std::isfinite(value) ? formatNumber(value, digits) : "null";
}

template <class T, class F>
std::string jsonArray(const std::vector<T>& items, F format) {
  std::string out = "[";
  for (std::size_t i = 0; i < items.size(); ++i) out += (i ? ", " : "") + format(items[i]);
  return out + "]";
}

constexpr std::size_t kFractions = std::size(kOpeningFractions);

// "opened_0.25": an opening-curve column's name.
std::string openedColumn(double fraction) { return "opened_" + formatNumber(fraction, 6); }

EvaluationSummary summarize(const std::string& object_id,
                            const std::vector<const EpisodeRecord*>& episodes,
                            std::size_t conditions, bool opening) {
  EvaluationSummary s;
  s.object_id = object_id;
  s.condition_rates.assign(conditions, 0);
  if (opening) {
    s.opened_counts.assign(kFractions, 0);
    for (const EpisodeRecord* r : episodes)
      for (std::size_t f = 0; f < kFractions; ++f)
        if (r->max_opened >= kOpeningFractions[f]) ++s.opened_counts[f];  // NaN: not reached
    for (const uint32_t count : s.opened_counts)
      s.opened_rates.push_back(episodes.empty() ? 0.0 : double(count) / double(episodes.size()));
    s.opened_low.assign(kFractions, 0);
    s.opened_high.assign(kFractions, 0);
  }
  double total_return = 0, total_steps = 0;
  for (const EpisodeRecord* r : episodes) {
    ++s.episodes;
    if (r->success) ++s.successes;
    if (r->success_once) ++s.successes_once;
    if (r->failed()) ++s.failures;
    for (std::size_t c = 0; c < conditions && c < r->flags.size(); ++c)
      s.condition_rates[c] += r->flags[c] ? 1 : 0;
    total_return += r->total_reward;
    total_steps += r->steps;
  }
  if (s.episodes > 0) {
    const double n = s.episodes;
    s.success_rate = s.successes / n;
    s.success_once_rate = s.successes_once / n;
    for (double& rate : s.condition_rates) rate /= n;
    s.mean_return = total_return / n;
    s.mean_steps = total_steps / n;
  }
  return s;
}

void writeSummaryJson(std::ostream& out, const EvaluationSummary& s,
                      const std::vector<std::string>& conditions, const std::string& indent) {
  if (s.objects)
    out << "{\"category\": " << escapeJson(s.object_id) << ", \"objects\": " << s.objects;
  else
    out << "{\"object\": " << escapeJson(s.object_id);
  out << ", \"episodes\": " << s.episodes
      << ", \"successes\": " << s.successes << ", \"failures\": " << s.failures
      << ", \"success_rate\": " << jsonNumber(s.success_rate, 6) << ", \"success_interval\": ["
      << jsonNumber(s.success_low, 6) << ", " << jsonNumber(s.success_high, 6) << "],\n"
      << indent << " \"success_once_rate\": " << jsonNumber(s.success_once_rate, 6)
      << ", \"success_once_interval\": [" << jsonNumber(s.success_once_low, 6) << ", "
      << jsonNumber(s.success_once_high, 6) << "], \"success_at_end_rate\": " << jsonNumber(s.success_rate, 6)
      << ", \"success_at_end_interval\": [" << jsonNumber(s.success_low, 6) << ", "
      << jsonNumber(s.success_high, 6) << "],\n"
      << indent << " \"condition_rates\": {";
  for (std::size_t c = 0; c < conditions.size(); ++c)
    out << (c ? ", " : "") << escapeJson(conditions[c]) << ": "
        << jsonNumber(c < s.condition_rates.size() ? s.condition_rates[c] : 0, 6);
  out << "},\n";
  // The opening curve (kOpeningFractions), where the task measures openings.
  if (!s.opened_counts.empty()) {
    out << indent << " \"opening_curve\": [";
    for (std::size_t f = 0; f < s.opened_counts.size(); ++f)
      out << (f ? ", " : "") << "{\"fraction\": " << jsonNumber(kOpeningFractions[f], 6)
          << ", \"episodes\": " << s.opened_counts[f] << ", \"rate\": " << jsonNumber(s.opened_rates[f], 6)
          << ", \"interval\": [" << jsonNumber(s.opened_low[f], 6) << ", " << jsonNumber(s.opened_high[f], 6)
          << "]}";
    out << "],\n";
  }
  out << indent << " \"mean_return\": " << jsonNumber(s.mean_return, 9)
      << ", \"mean_steps\": " << jsonNumber(s.mean_steps, 6) << "}";
}

std::string formatInterval(double low, double high) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(3) << "[" << low << ", " << high << "]";
  return out.str();
}

// The intervals of a summary pooled over objects (the overall line, a
// category's): a bootstrap that resamples those objects' counts.
void calcPooledIntervals(EvaluationSummary& pooled, const std::vector<const EvaluationSummary*>& objects) {
  std::vector<uint32_t> successes, successes_once, episodes;
  std::vector<std::vector<uint32_t>> opened(pooled.opened_counts.size());
  for (const EvaluationSummary* s : objects) {
    for (std::size_t f = 0; f < s->opened_counts.size() && f < opened.size(); ++f)
      opened[f].push_back(s->opened_counts[f]);
    successes.push_back(s->successes);
    successes_once.push_back(s->successes_once);
    episodes.push_back(s->episodes);
  }
  calcOverallInterval(successes, episodes, pooled.success_low, pooled.success_high);
  calcOverallInterval(successes_once, episodes, pooled.success_once_low, pooled.success_once_high);
  for (std::size_t f = 0; f < opened.size(); ++f)
    calcOverallInterval(opened[f], episodes, pooled.opened_low[f], pooled.opened_high[f]);
}

}  // namespace

std::map<std::string, std::string> getObjectCategories(const EvaluationTaskInfo& task) {
  std::map<std::string, std::string> categories;
  for (std::size_t i = 0; i < task.split_objects.size() && i < task.split_categories.size(); ++i)
    if (!task.split_categories[i].empty()) categories[task.split_objects[i]] = task.split_categories[i];
  return categories;
}

void summarizeEvaluation(EvaluationResult& result) {
  const std::size_t conditions = result.task.condition_names.size();
  std::vector<std::string> order;
  std::map<std::string, std::vector<const EpisodeRecord*>> groups;
  std::vector<const EpisodeRecord*> all;
  for (const EpisodeSpec& spec : result.planned)
    if (!groups.count(spec.object_id)) {
      order.push_back(spec.object_id);
      groups[spec.object_id];
    }
  for (const EpisodeRecord& r : result.episodes) {
    groups[r.spec.object_id].push_back(&r);
    all.push_back(&r);
  }
  // The opening curve where the task measures openings (any episode has).
  const bool opening = std::any_of(result.episodes.begin(), result.episodes.end(),
                                   [](const EpisodeRecord& r) { return std::isfinite(r.max_opened); });
  result.objects.clear();
  for (const std::string& object : order)
    if (!groups[object].empty())
      result.objects.push_back(summarize(object, groups[object], conditions, opening));
  result.overall = summarize("all", all, conditions, opening);
  std::vector<const EvaluationSummary*> every;
  for (EvaluationSummary& s : result.objects) {
    calcWilsonInterval(s.successes, s.episodes, s.success_low, s.success_high);
    calcWilsonInterval(s.successes_once, s.episodes, s.success_once_low, s.success_once_high);
    for (std::size_t f = 0; f < s.opened_counts.size(); ++f)
      calcWilsonInterval(s.opened_counts[f], s.episodes, s.opened_low[f], s.opened_high[f]);
    every.push_back(&s);
  }
  calcPooledIntervals(result.overall, every);

  // Per category, where the task names objects' categories (PartNet
  // folders): the category's episodes pooled, its interval a bootstrap
  // over its objects as the overall line's is over all. An object without
  // one among objects with one counts as "(none)".
  result.categories.clear();
  const std::map<std::string, std::string> categories = getObjectCategories(result.task);
  if (categories.empty()) return;
  std::map<std::string, std::vector<const EvaluationSummary*>> by_category;
  for (const EvaluationSummary& s : result.objects) {
    const auto found = categories.find(s.object_id);
    by_category[found == categories.end() ? "(none)" : found->second].push_back(&s);
  }
  for (const auto& [category, objects] : by_category) {
    std::vector<const EpisodeRecord*> episodes;
    for (const EvaluationSummary* s : objects)
      episodes.insert(episodes.end(), groups[s->object_id].begin(), groups[s->object_id].end());
    EvaluationSummary pooled = summarize(category, episodes, conditions, opening);
    pooled.objects = uint32_t(objects.size());
    calcPooledIntervals(pooled, objects);
    result.categories.push_back(std::move(pooled));
  }
}

void printEvaluationTable(std::ostream& out, const EvaluationResult& result) {
  // The last condition, "success", is the success rate's column already.
  std::vector<std::string> conditions = result.task.condition_names;
  if (!conditions.empty() && conditions.back() == "success") conditions.pop_back();
  std::size_t object_width = 8;
  for (const EvaluationSummary& s : result.objects)
    object_width = std::max(object_width, s.object_id.size() + 2);
  std::vector<std::size_t> widths;
  for (const std::string& c : conditions) widths.push_back(std::max<std::size_t>(c.size() + 2, 9));
  // Without the early done success_once differs from success (at the end).
  const bool once = !result.options.early_done;
  out << std::left << std::setw(int(object_width)) << "object" << std::right << std::setw(9)
      << "episodes" << std::setw(10) << "success" << std::setw(17) << "95% interval";
  if (once) out << std::setw(7) << "once" << std::setw(17) << "95% interval";
  for (std::size_t c = 0; c < conditions.size(); ++c)
    out << std::setw(int(widths[c])) << conditions[c];
  out << std::setw(9) << "failed" << std::setw(13) << "mean return" << std::setw(12) << "mean steps"
      << "\n";
  auto row = [&](const EvaluationSummary& s) {
    out << std::left << std::setw(int(object_width)) << s.object_id << std::right << std::setw(9)
        << s.episodes << std::setw(10) << std::fixed << std::setprecision(3) << s.success_rate
        << std::setw(17) << formatInterval(s.success_low, s.success_high);
    if (once)
      out << std::setw(7) << s.success_once_rate << std::setw(17)
          << formatInterval(s.success_once_low, s.success_once_high);
    for (std::size_t c = 0; c < conditions.size(); ++c)
      out << std::setw(int(widths[c])) << s.condition_rates[c];
    out << std::setw(9) << s.failures << std::setw(13) << std::setprecision(3) << s.mean_return
        << std::setw(12) << std::setprecision(1) << s.mean_steps << "\n";
    out.unsetf(std::ios::fixed);
  };
  for (const EvaluationSummary& s : result.objects) row(s);
  std::size_t width = object_width + 9 + 10 + 17 + 9 + 13 + 12 + (once ? 7 + 17 : 0);
  for (std::size_t w : widths) width += w;
  out << std::string(width, '-') << "\n";
  row(result.overall);
  if (!result.categories.empty()) {
    out << "\nper category (its objects' episodes; interval: bootstrap over its objects):\n";
    for (const EvaluationSummary& s : result.categories) row(s);
  }
  const EvaluationSummary& all = result.overall;
  if (!all.opened_counts.empty()) {
    out << "\nopened at least (at any step):";
    for (std::size_t f = 0; f < all.opened_counts.size(); ++f)
      out << (f ? "," : "") << " " << formatNumber(100 * kOpeningFractions[f], 3) << " % " << std::fixed
          << std::setprecision(3) << all.opened_rates[f] << " " << formatInterval(all.opened_low[f], all.opened_high[f]);
    out.unsetf(std::ios::fixed);
    out << "\n";
  }

  std::map<std::string, std::size_t> reasons;
  const EpisodeRecord* first = nullptr;
  for (const EpisodeRecord& r : result.episodes)
    if (r.failed()) {
      ++reasons[r.failure];
      if (!first) first = &r;
    }
  if (first) {
    out << "\nfailed episodes: " << result.overall.failures << " (";
    bool comma = false;
    for (const auto& [reason, count] : reasons) {
      out << (comma ? ", " : "") << reason << " " << count;
      comma = true;
    }
    out << "), counted as unsuccessful; the first: object " << first->spec.object_id << ", seed "
        << first->spec.seed << ", " << first->failure << ": " << first->message << "\n";
  }
}

void writeSummaryCsv(std::ostream& out, const EvaluationResult& result) {
  const std::vector<std::string>& conditions = result.task.condition_names;
  out << "object,episodes,successes,failures,success_rate,success_low,success_high,successes_once,"
         "success_once_rate,success_once_low,success_once_high";
  for (const std::string& c : conditions) out << "," << escapeCsv("condition_" + c);
  if (!result.overall.opened_counts.empty())
    for (const double fraction : kOpeningFractions) {
      const std::string column = openedColumn(fraction);
      out << "," << column << "," << column << "_low," << column << "_high";
    }
  out << ",mean_return,mean_steps\n";
  auto row = [&](const EvaluationSummary& s) {
    out << escapeCsv(s.object_id) << "," << s.episodes << "," << s.successes << "," << s.failures
        << "," << formatRate(s.success_rate) << "," << formatRate(s.success_low) << ","
        << formatRate(s.success_high) << "," << s.successes_once << "," << formatRate(s.success_once_rate)
        << "," << formatRate(s.success_once_low) << "," << formatRate(s.success_once_high);
    for (double rate : s.condition_rates) out << "," << formatRate(rate);
    for (std::size_t f = 0; f < s.opened_counts.size(); ++f)
      out << "," << formatRate(s.opened_rates[f]) << "," << formatRate(s.opened_low[f]) << ","
          << formatRate(s.opened_high[f]);
    out << "," << formatReturn(s.mean_return) << "," << formatRate(s.mean_steps) << "\n";
  };
  for (const EvaluationSummary& s : result.objects) row(s);
  row(result.overall);
}

void writeEpisodesCsv(std::ostream& out, const EvaluationResult& result) {
  const std::vector<std::string>& conditions = result.task.condition_names;
  out << "index,object,level,seed,steps,return,success,success_once,success_at_end";
  for (const std::string& c : conditions) out << "," << escapeCsv(c);
  out << ",max_opened,failure,failure_step,message\n";
  for (const EpisodeRecord& r : result.episodes) {
    out << r.spec.index << "," << escapeCsv(r.spec.object_id) << "," << r.spec.level << ","
        << r.spec.seed << "," << r.steps << "," << formatReturn(r.total_reward) << ","
        << (r.success ? 1 : 0) << "," << (r.success_once ? 1 : 0) << "," << (r.success ? 1 : 0);
    for (std::size_t c = 0; c < conditions.size(); ++c)
      out << "," << (c < r.flags.size() && r.flags[c] ? 1 : 0);
    // Empty where the task measures no opening, and for failed episodes.
    out << "," << (std::isnan(r.max_opened) ? "" : formatNumber(r.max_opened, 9));
    out << "," << escapeCsv(r.failure) << ",";
    if (r.failure_step >= 0) out << r.failure_step;
    out << "," << escapeCsv(r.message) << "\n";
  }
}

void writeEvaluationJson(std::ostream& out, const EvaluationResult& result) {
  const EvaluationOptions& o = result.options;
  const std::vector<std::string>& conditions = result.task.condition_names;
  auto quote = [](const std::string& s) { return escapeJson(s); };
  std::vector<std::string> objects;
  for (const EpisodeSpec& spec : result.planned)
    if (std::find(objects.begin(), objects.end(), spec.object_id) == objects.end())
      objects.push_back(spec.object_id);
  std::map<std::string, std::size_t> reasons;
  for (const EpisodeRecord& r : result.episodes)
    if (r.failed()) ++reasons[r.failure];

  out << "{\n";
  out << "  \"manibench_version\": " << quote(getManibenchVersion()) << ",\n";
  out << "  \"build_id\": " << quote(getManibenchBuildId()) << ",\n";
  out << "  \"task\": " << quote(o.task) << ",\n";
  out << "  \"observation_mode\": " << quote(toString(result.task.observation_mode)) << ",\n";
  out << "  \"controller\": " << quote(result.task.controller) << ",\n";
  out << "  \"policy\": {\"name\": " << quote(o.policy)
      << ", \"library\": " << quote(result.policy_library)
      << ", \"version\": " << quote(result.policy_library_version)
      << ", \"config\": " << quote(o.policy_config) << "},\n";
  out << "  \"split\": " << quote(o.split) << ",\n";
  out << "  \"seed\": " << o.seed << ",\n";
  // A shard's files (--shard I/N) say which share they hold; merged or
  // single runs' files have no such line.
  if (o.shards > 1) out << "  \"shard\": \"" << o.shard + 1 << "/" << o.shards << "\",\n";
  out << "  \"objects\": " << jsonArray(objects, quote) << ",\n";
  out << "  \"levels\": " << jsonArray(o.levels, [](uint64_t v) { return std::to_string(v); })
      << ",\n";
  // ManiSkill v1's B.4 (true, the default) or to the time limit
  // (--no-early-done): what success_once and success_at_end mean.
  out << "  \"early_done\": " << (o.early_done ? "true" : "false") << ",\n";
  out << "  \"step_timeout_s\": " << jsonNumber(o.step_timeout, 6) << ",\n";
  // Where the policy ran: a sandboxed process with its limits, or the
  // worker's own process (--trusted-policy).
  if (o.sandbox_policy)
    out << "  \"policy_process\": {\"sandbox\": true, \"cpu_limit_s\": "
        << jsonNumber(o.policy_cpu_limit, 6) << ", \"memory_limit_bytes\": "
        << o.policy_memory_limit << ", \"output_limit_bytes\": " << o.policy_output_limit
        << ", \"facilities\": " << quote(describeSandbox()) << "},\n";
  else
    out << "  \"policy_process\": {\"sandbox\": false},\n";
  out << "  \"configuration\": " << jsonArray(o.config_notes, quote) << ",\n";
  out << "  \"max_episode_steps\": " << result.task.max_episode_steps << ",\n";
  out << "  \"success_conditions\": " << jsonArray(conditions, quote) << ",\n";
  out << "  \"episodes_planned\": " << result.planned.size() << ",\n";
  out << "  \"episodes_run\": " << result.episodes.size() << ",\n";
  out << "  \"complete\": " << (result.interrupted ? "false" : "true") << ",\n";
  out << "  \"stop_reason\": " << quote(result.stop_reason) << ",\n";
  out << "  \"failures\": {";
  bool comma = false;
  for (const auto& [reason, count] : reasons) {
    out << (comma ? ", " : "") << quote(reason) << ": " << count;
    comma = true;
  }
  out << "},\n";
  out << "  \"per_object\": [";
  for (std::size_t i = 0; i < result.objects.size(); ++i) {
    out << (i ? ",\n    " : "\n    ");
    writeSummaryJson(out, result.objects[i], conditions, "    ");
  }
  out << "\n  ],\n";
  // Only where the task names categories: other reports stay as they were.
  if (!result.categories.empty()) {
    out << "  \"per_category\": [";
    for (std::size_t i = 0; i < result.categories.size(); ++i) {
      out << (i ? ",\n    " : "\n    ");
      writeSummaryJson(out, result.categories[i], conditions, "    ");
    }
    out << "\n  ],\n";
  }
  out << "  \"intervals\": {\"per_object\": \"Wilson score, 95 %\", \"overall\": \"bootstrap over objects, 95 % "
         "percentile, "
      << kBootstrapResamples << " resamples, SplitMix64 seed " << kBootstrapSeed
      << ", widened to the pooled episodes' Wilson interval\"},\n";
  out << "  \"overall\": ";
  writeSummaryJson(out, result.overall, conditions, "  ");
  out << ",\n";
  // Timings last and on one line: everything above is the same in two
  // runs of the same evaluation, whatever the number of workers.
  out << "  \"timing\": {\"seconds\": " << jsonNumber(result.seconds, 6)
      << ", \"episodes_per_second\": "
      << jsonNumber(result.seconds > 0 ? result.episodes.size() / result.seconds : 0, 6)
      << ", \"workers\": " << o.workers << ", \"worker_restarts\": " << result.worker_restarts
      << "}\n";
  out << "}\n";
}

std::vector<std::string> writeEvaluationFiles(const std::string& directory,
                                              const EvaluationResult& result) {
  namespace fs = std::filesystem;
  std::error_code error;
  fs::create_directories(directory, error);
  if (error)
    throw EvaluationError("cannot create the output directory '" + directory +
                          "': " + error.message());
  std::vector<std::string> written;
  auto write = [&](const std::string& name,
                   void (*writer)(std::ostream&, const EvaluationResult&)) {
    const std::string path = (fs::path(directory) / name).string();
    const std::string partial = path + ".partial";
    {
      std::ofstream file(partial, std::ios::binary | std::ios::trunc);
      if (!file) throw EvaluationError("cannot write '" + partial + "'");
      writer(file, result);
      file.flush();
      if (!file) throw EvaluationError("cannot write '" + partial + "' (disk full?)");
    }
    // Renamed into place, so a reader never sees half a file.
    fs::rename(partial, path, error);
    if (error) throw EvaluationError("cannot rename '" + partial + "': " + error.message());
    written.push_back(path);
  };
  write("summary.csv", writeSummaryCsv);
  write("episodes.csv", writeEpisodesCsv);
  write("summary.json", writeEvaluationJson);
  write("certificate.json", writeCertificateJson);
  return written;
}

}  // namespace manibench
