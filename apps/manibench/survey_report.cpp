#include "survey_report.hpp"

#include <manibench/outcome.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <ostream>
#include <set>
#include <sstream>
#include <stdexcept>

namespace manibench::cli {

namespace {

std::string csvField(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (const char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

std::string formatNumber(double x, int digits = 4) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.*g", digits, x);
  return buffer;
}

std::string percent(int part, int whole) {
  return whole > 0 ? formatNumber(100.0 * part / whole, 3) + " %" : "-";
}

// "grasp_lost 2, time_limit 1": the failures' outcomes, most first.
std::string describeOutcomes(const std::map<std::string, int>& outcomes) {
  std::vector<std::pair<int, std::string>> sorted;
  for (const auto& [name, count] : outcomes)
    if (name != outcome::kSuccess) sorted.push_back({-count, name});
  std::sort(sorted.begin(), sorted.end());
  std::string text;
  for (const auto& [count, name] : sorted) text += (text.empty() ? "" : ", ") + name + " " + std::to_string(-count);
  return text;
}

void writeFile(const std::filesystem::path& path, const std::string& text, std::vector<std::string>& written) {
  std::ofstream out(path);
  out << text;
  out.close();
  if (!out) throw std::runtime_error("cannot write " + path.string());
  written.push_back(path.string());
}

// Outcome colours for the figure: success green, then the failures.
const char* colourOf(const std::string& name) {
  static const std::map<std::string, const char*> colours = {
      {outcome::kSuccess, "#3a923a"},     {outcome::kNotStatic, "#9acd32"}, {outcome::kWrongWay, "#8c564b"},
      {outcome::kBlocked, "#d62728"},     {outcome::kNeverReached, "#ff7f0e"}, {outcome::kGraspLost, "#9467bd"},
      {outcome::kNotMoved, "#e377c2"},    {outcome::kNotGrasped, "#bcbd22"}, {outcome::kTimeLimit, "#1f77b4"},
      {outcome::kUnknown, "#7f7f7f"},     {outcome::kError, "#000000"},      {outcome::kRefused, "#c7c7c7"}};
  const auto it = colours.find(name);
  return it == colours.end() ? "#7f7f7f" : it->second;
}

}  // namespace

SurveyReport::SurveyReport(std::string task, std::string policy, std::vector<uint64_t> levels, uint64_t seed)
    : task_(std::move(task)), policy_(std::move(policy)), levels_(std::move(levels)), seed_(seed) {}

void SurveyReport::addCategory(const std::string& category, const std::string& dir, double listing_s,
                               const std::string& error) {
  // Two folders of one category (two downloads' Bucket folders) are one
  // category: their objects are summed, not listed once per folder.
  for (Category& c : categories_)
    if (c.name == category) {
      c.dir += ", " + dir;
      c.listing_s += listing_s;
      if (!error.empty()) c.error += (c.error.empty() ? "" : "; ") + error;
      return;
    }
  categories_.push_back({category, dir, error, listing_s});
}

void SurveyReport::addRefused(const std::string& category, const std::string& object, const std::string& reason) {
  SurveyObject o;
  o.category = category;
  o.object = object;
  o.refused = true;
  o.reason = reason;
  objects_.push_back(o);
}

void SurveyReport::addObject(const SurveyObject& object) { objects_.push_back(object); }
void SurveyReport::addEpisode(const SurveyEpisode& episode) { episodes_.push_back(episode); }

std::vector<SurveyReport::Summary> SurveyReport::summarize() const {
  std::vector<Summary> out;
  Summary all;
  all.category = "all";
  for (const Category& c : categories_) {
    Summary s;
    s.category = c.name;
    for (const SurveyObject& o : objects_)
      if (o.category == c.name) {
        (o.refused ? s.refused : s.objects)++;
        s.left_out += int(o.left_out.size());
      }
    std::map<std::string, bool> solved;
    for (const SurveyEpisode& e : episodes_) {
      if (e.category != c.name) continue;
      ++s.episodes;
      if (e.success) ++s.successes;
      ++s.outcomes[e.outcome];
      solved[e.object_id] = solved[e.object_id] || e.success;
    }
    s.targets = int(solved.size());
    for (const auto& [id, ok] : solved) s.targets_solved += ok ? 1 : 0;
    all.objects += s.objects;
    all.refused += s.refused;
    all.targets += s.targets;
    all.left_out += s.left_out;
    all.targets_solved += s.targets_solved;
    all.episodes += s.episodes;
    all.successes += s.successes;
    for (const auto& [name, count] : s.outcomes) all.outcomes[name] += count;
    out.push_back(s);
  }
  out.push_back(all);
  return out;
}

void SurveyReport::print(std::ostream& out) const {
  out << "\nper object (" << task_ << ", policy " << policy_ << ", " << levels_.size() << " levels, seed " << seed_
      << "):\n";
  for (const Category& c : categories_) {
    if (!c.error.empty()) out << "  " << c.name << ": no object loads: " << c.error << "\n";
    for (const SurveyObject& o : objects_)
      if (o.category == c.name && o.refused) out << "  " << std::left << std::setw(22) << o.object << " refused: " << o.reason << "\n";
    for (const SurveyObject& o : objects_)
      if (o.category == c.name)
        for (const std::string& note : o.left_out)
          out << "  " << std::left << std::setw(22) << o.object << " left out " << note << "\n";
    std::vector<std::string> ids;
    for (const SurveyEpisode& e : episodes_)
      if (e.category == c.name && (ids.empty() || ids.back() != e.object_id)) ids.push_back(e.object_id);
    for (const std::string& id : ids) {
      int n = 0, ok = 0;
      int64_t first = -1;
      std::map<std::string, int> outcomes;
      for (const SurveyEpisode& e : episodes_) {
        if (e.category != c.name || e.object_id != id) continue;
        ++n;
        if (e.success) {
          ++ok;
          if (first < 0) first = int64_t(e.level);
        }
        ++outcomes[e.outcome];
      }
      out << "  " << std::left << std::setw(22) << id << std::right << std::setw(3) << ok << "/" << std::left
          << std::setw(3) << n << (first >= 0 ? " first success at level " + std::to_string(first) : " no success");
      const std::string failures = describeOutcomes(outcomes);
      if (!failures.empty()) out << "; " << failures;
      out << "\n";
    }
  }
  out << "\nper category:\n"
      << "  " << std::left << std::setw(18) << "category" << std::right << std::setw(8) << "objects" << std::setw(8)
      << "refused" << std::setw(8) << "targets" << std::setw(10) << "left out" << std::setw(9) << "episodes"
      << std::setw(10) << "success"
      << std::setw(14) << "solved" << "  failures\n";
  for (const Summary& s : summarize())
    out << "  " << std::left << std::setw(18) << s.category << std::right << std::setw(8) << s.objects
        << std::setw(8) << s.refused << std::setw(8) << s.targets << std::setw(10) << s.left_out << std::setw(9)
        << s.episodes << std::setw(10)
        << percent(s.successes, s.episodes) << std::setw(14)
        << (std::to_string(s.targets_solved) + "/" + std::to_string(s.targets)) << "  "
        << describeOutcomes(s.outcomes) << "\n";
  out << "(solved: targets with a success within the levels; left out: parts the task does not make targets,\n"
         " named above with the reason)\n";
}

std::vector<std::string> SurveyReport::write(const std::string& dir) const {
  namespace fs = std::filesystem;
  fs::create_directories(dir);
  std::vector<std::string> written;
  std::ostringstream episodes;
  episodes << "category,object,object_id,level,seed,success,outcome,steps,reward,max_progress,final_progress,"
              "first_reached_step,first_held_step,message\n";
  for (const SurveyEpisode& e : episodes_)
    episodes << csvField(e.category) << "," << csvField(e.object) << "," << csvField(e.object_id) << "," << e.level
             << "," << e.seed << "," << (e.success ? 1 : 0) << "," << e.outcome << "," << e.steps << ","
             << formatNumber(e.reward, 17) << "," << formatNumber(e.max_progress, 6) << ","
             << formatNumber(e.final_progress, 6) << "," << e.first_reached << "," << e.first_held << ","
             << csvField(e.message) << "\n";
  writeFile(fs::path(dir) / "episodes.csv", episodes.str(), written);
  std::ostringstream objects;
  objects << "category,object,status,first_load_s,again_s,reason,left_out\n";
  for (const SurveyObject& o : objects_) {
    std::string left_out;
    for (const std::string& note : o.left_out) left_out += (left_out.empty() ? "" : "; ") + note;
    objects << csvField(o.category) << "," << csvField(o.object) << "," << (o.refused ? "refused" : "loaded") << ","
            << (o.refused ? "" : formatNumber(o.first_load_s, 4)) << "," << (o.refused ? "" : formatNumber(o.again_s, 4))
            << "," << csvField(o.reason) << "," << csvField(left_out) << "\n";
  }
  writeFile(fs::path(dir) / "objects.csv", objects.str(), written);

  nlohmann::json json;
  json["task"] = task_;
  json["policy"] = policy_;
  json["levels"] = levels_;
  json["seed"] = seed_;
  for (const Category& c : categories_)
    json["folders"].push_back({{"category", c.name}, {"dir", c.dir}, {"listing_seconds", c.listing_s}, {"error", c.error}});
  for (const Summary& s : summarize())
    json["categories"].push_back({{"category", s.category},
                                  {"objects", s.objects},
                                  {"refused", s.refused},
                                  {"targets", s.targets},
                                  {"targets_left_out", s.left_out},
                                  {"targets_solved", s.targets_solved},
                                  {"episodes", s.episodes},
                                  {"successes", s.successes},
                                  {"success_rate", s.episodes ? double(s.successes) / s.episodes : 0.0},
                                  {"outcomes", s.outcomes}});
  writeFile(fs::path(dir) / "survey.json", json.dump(2) + "\n", written);

  // One stacked bar per category: the episodes' outcomes, success first.
  const std::vector<Summary> summaries = summarize();
  const int bar = 46, gap = 24, left = 60, top = 40, height = 260;
  const int width = left + int(summaries.size()) * (bar + gap) + 200;
  std::ostringstream svg;
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << top + height + 70
      << "\" font-family=\"sans-serif\" font-size=\"11\">\n"
      << "<text x=\"" << left << "\" y=\"20\" font-size=\"13\">" << task_ << ", " << policy_ << ": outcomes per category ("
      << levels_.size() << " levels, seed " << seed_ << ")</text>\n";
  for (int k = 0; k <= 4; ++k) {
    const int y = top + height - k * height / 4;
    svg << "<line x1=\"" << left - 4 << "\" y1=\"" << y << "\" x2=\"" << width - 200 << "\" y2=\"" << y
        << "\" stroke=\"#ddd\"/><text x=\"" << left - 8 << "\" y=\"" << y + 4 << "\" text-anchor=\"end\">" << 25 * k
        << " %</text>\n";
  }
  std::set<std::string> used;
  for (std::size_t i = 0; i < summaries.size(); ++i) {
    const Summary& s = summaries[i];
    const int x = left + int(i) * (bar + gap);
    double y = top + height;
    for (const std::string& name : listOutcomes()) {
      const auto it = s.outcomes.find(name);
      if (it == s.outcomes.end() || s.episodes == 0) continue;
      used.insert(name);
      const double h = double(height) * it->second / s.episodes;
      y -= h;
      svg << "<rect x=\"" << x << "\" y=\"" << formatNumber(y, 6) << "\" width=\"" << bar << "\" height=\""
          << formatNumber(h, 6) << "\" fill=\"" << colourOf(name) << "\"><title>" << name << ": " << it->second
          << "</title></rect>\n";
    }
    svg << "<text x=\"" << x + bar / 2 << "\" y=\"" << top + height + 14 << "\" text-anchor=\"middle\">" << s.category
        << "</text><text x=\"" << x + bar / 2 << "\" y=\"" << top + height + 28 << "\" text-anchor=\"middle\">"
        << percent(s.successes, s.episodes) << "</text><text x=\"" << x + bar / 2 << "\" y=\"" << top + height + 42
        << "\" text-anchor=\"middle\" fill=\"#666\">" << s.episodes << " ep.</text>\n";
  }
  int legend = top;
  for (const std::string& name : listOutcomes()) {
    if (!used.count(name)) continue;
    svg << "<rect x=\"" << width - 180 << "\" y=\"" << legend << "\" width=\"12\" height=\"12\" fill=\""
        << colourOf(name) << "\"/><text x=\"" << width - 162 << "\" y=\"" << legend + 10 << "\">" << name
        << "</text>\n";
    legend += 18;
  }
  svg << "</svg>\n";
  writeFile(fs::path(dir) / "survey.svg", svg.str(), written);
  return written;
}

}  // namespace manibench::cli
