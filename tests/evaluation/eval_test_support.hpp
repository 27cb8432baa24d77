// What the evaluation kit's tests share: a temporary folder, the CSV
// files as rows, `manibench eval` with an output folder.
#pragma once

#include <stdlib.h>

#include <filesystem>
#include <functional>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "test_support.hpp"

namespace manibench {
namespace fs = std::filesystem;

// A fresh directory, removed with the object.
class TempDir {
 public:
  TempDir() {
    char path[] = "/tmp/manibench_eval_XXXXXX";
    if (!mkdtemp(path)) throw std::runtime_error("mkdtemp failed");
    path_ = path;
  }
  ~TempDir() { fs::remove_all(path_); }
  fs::path operator/(const std::string& name) const { return path_ / name; }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// Rows of a CSV file as maps from the header's names (quotes as RFC 4180).
inline std::vector<std::map<std::string, std::string>> readCsv(const fs::path& path) {
  const std::string text = testing::readFile(path);
  std::vector<std::vector<std::string>> rows(1);
  std::string field;
  bool quoted = false, row_started = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (quoted) {
      if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') {
        field += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        field += c;
      }
      continue;
    }
    row_started = true;
    if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      rows.back().push_back(field);
      field.clear();
    } else if (c == '\n') {
      rows.back().push_back(field);
      field.clear();
      rows.emplace_back();
      row_started = false;
    } else {
      field += c;
    }
  }
  if (row_started) rows.back().push_back(field);
  if (rows.back().empty()) rows.pop_back();
  std::vector<std::map<std::string, std::string>> out;
  for (std::size_t r = 1; r < rows.size(); ++r) {
    EXPECT_EQ(rows[r].size(), rows[0].size()) << path << " row " << r;
    std::map<std::string, std::string> row;
    for (std::size_t c = 0; c < rows[0].size() && c < rows[r].size(); ++c)
      row[rows[0][c]] = rows[r][c];
    out.push_back(row);
  }
  return out;
}

// summary.json without its one timing line (wall times differ between runs).
inline std::string withoutTiming(const std::string& json) {
  std::istringstream in(json);
  std::string line, out;
  while (std::getline(in, line))
    if (line.find("\"timing\"") == std::string::npos) out += line + "\n";
  return out;
}

// `common` arguments, then `extra`.
inline std::vector<std::string> joinArguments(std::vector<std::string> common, const std::vector<std::string>& extra) {
  common.insert(common.end(), extra.begin(), extra.end());
  return common;
}

inline testing::CommandResult runEval(const TempDir& out, std::vector<std::string> arguments,
                               const std::vector<std::string>& environment = {},
                               const std::function<void()>& in_child = {}) {
  arguments.insert(arguments.begin(), "eval");
  arguments.insert(arguments.end(), {"--out", out.path().string(), "--no-progress"});
  return testing::runCli(arguments, environment, in_child);
}


}  // namespace manibench
