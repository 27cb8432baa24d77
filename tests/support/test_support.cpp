#include "test_support.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace manibench::testing {

long readRssKb() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  return -1;
}

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

FixtureCopy::FixtureCopy(const std::string& fixture) {
  static int counter = 0;
  const std::filesystem::path root = std::filesystem::temp_directory_path() /
                                     ("manibench_" + fixture + "_" + std::to_string(::getpid()) + "_" +
                                      std::to_string(counter++));
  std::filesystem::remove_all(root);
  std::filesystem::copy(std::string(MANIBENCH_TEST_SOURCE_DIR) + "/tests/fixtures/" + fixture, root,
                        std::filesystem::copy_options::recursive);
  folder_ = root.string();
}

FixtureCopy::~FixtureCopy() {
  std::error_code ignored;
  std::filesystem::remove_all(folder_, ignored);
}

void FixtureCopy::replace(const std::string& name, const std::string& from, const std::string& to) {
  std::string text = readFile(file(name));
  const std::size_t at = text.find(from);
  if (at == std::string::npos) {
    ADD_FAILURE() << "'" << from << "' is not in " << file(name);
    return;
  }
  text.replace(at, from.size(), to);
  std::ofstream(file(name)) << text;
}

void makeFlap(FixtureCopy& copy, bool bottom) {
  const std::string y = bottom ? "-0.395" : "0.395";
  for (int i = 0; i < 4; ++i)
    copy.replace("100001/mobility.urdf", "<origin xyz=\"0.295 0 -0.22\"/>", "<origin xyz=\"0 " + std::string(bottom ? "0.395" : "-0.395") + " -0.2\"/>");
  copy.replace("100001/mobility.urdf", "<origin xyz=\"-0.295 0 0.22\"/>\n    <axis xyz=\"0 -1 0\"/>",
               "<origin xyz=\"0 " + y + " 0.2\"/>\n    <axis xyz=\"" + (bottom ? "1" : "-1") + " 0 0\"/>");
}

CommandResult runCli(const std::vector<std::string>& arguments,
                     const std::vector<std::string>& environment,
                     const std::function<void()>& in_child) {
  return runProgram(MANIBENCH_TEST_CLI, arguments, environment, in_child);
}

CommandResult runProgram(const std::string& program, const std::vector<std::string>& arguments,
                         const std::vector<std::string>& environment, const std::function<void()>& in_child) {
  char out_template[] = "/tmp/manibench_cli_out_XXXXXX";
  char err_template[] = "/tmp/manibench_cli_err_XXXXXX";
  const int out_fd = mkstemp(out_template);
  const int err_fd = mkstemp(err_template);
  if (out_fd < 0 || err_fd < 0) throw std::runtime_error("mkstemp failed");
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    dup2(out_fd, 1);
    dup2(err_fd, 2);
    for (const std::string& assignment : environment) putenv(const_cast<char*>(assignment.c_str()));
    std::vector<char*> argv;
    std::string name = program;
    argv.push_back(name.data());
    std::vector<std::string> copies = arguments;
    for (std::string& a : copies) argv.push_back(a.data());
    argv.push_back(nullptr);
    if (in_child) in_child();
    execvp(name.c_str(), argv.data());
    _exit(127);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  close(out_fd);
  close(err_fd);
  CommandResult result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  result.out = readFile(out_template);
  result.err = readFile(err_template);
  std::remove(out_template);
  std::remove(err_template);
  return result;
}

void expectMentions(const std::string& message, const std::vector<std::string>& parts) {
  for (const std::string& part : parts)
    EXPECT_TRUE(contains(message, part)) << "'" << part << "' is not in: " << message;
}

}  // namespace manibench::testing
