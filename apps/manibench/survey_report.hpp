// What `manibench survey` found (command_survey.cpp): per episode, per
// object and per category, as tables, CSV, JSON and an SVG figure.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <map>
#include <string>
#include <vector>

namespace manibench::cli {

struct SurveyEpisode {
  std::string category, object, object_id;  // object: the physical object; object_id: the task's id
  uint64_t level = 0, seed = 0;
  bool success = false;
  std::string outcome;  // manibench/outcome.hpp
  uint32_t steps = 0;
  double reward = 0;
  double max_progress = -1, final_progress = -1;  // -1: no progress signal
  int first_reached = -1, first_held = -1;        // step, -1: never
  std::string message;                            // an error's
};

struct SurveyObject {
  std::string category, object;
  bool refused = false;
  std::string reason;  // why it was refused
  // Its parts the task leaves out as targets, each with why ("link_0: it
  // reaches 2.5 cm into the ground before it opens 90 %").
  std::vector<std::string> left_out;
  double first_load_s = 0, again_s = 0;  // its scene built in this process the first time, then again
};

class SurveyReport {
 public:
  SurveyReport(std::string task, std::string policy, std::vector<uint64_t> levels, uint64_t seed);
  void addCategory(const std::string& category, const std::string& dir, double listing_s, const std::string& error);
  void addRefused(const std::string& category, const std::string& object, const std::string& reason);
  void addObject(const SurveyObject& object);
  void addEpisode(const SurveyEpisode& episode);

  // Per object (each task object id: a cabinet's target link), then per
  // category and overall.
  void print(std::ostream& out) const;
  // episodes.csv, objects.csv, survey.json, survey.svg in `dir`; the paths.
  std::vector<std::string> write(const std::string& dir) const;

  // Per category: the summary the table, the JSON and the figure show.
  struct Summary {
    std::string category;
    int objects = 0, refused = 0;  // physical objects loaded, refused
    int targets = 0;               // task object ids with episodes
    int left_out = 0;              // targets of loaded objects left out (no episodes)
    int targets_solved = 0;        // of those, with a success in the levels
    int episodes = 0, successes = 0;
    std::map<std::string, int> outcomes;
  };
  std::vector<Summary> summarize() const;

 private:
  std::string task_, policy_;
  std::vector<uint64_t> levels_;
  uint64_t seed_;
  struct Category {
    std::string name, dir, error;
    double listing_s = 0;
  };
  std::vector<Category> categories_;
  std::vector<SurveyObject> objects_;
  std::vector<SurveyEpisode> episodes_;
};

}  // namespace manibench::cli
