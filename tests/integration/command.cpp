#include "command.hpp"

#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <regex>

namespace cosim::testing {

CommandResult run_command(const std::string& command, int time_limit_seconds) {
  CommandResult result;
  const auto start = std::chrono::steady_clock::now();
  const std::string limited =
      fmt::format("timeout -s KILL {} {} 2>&1", time_limit_seconds, command);
  FILE* pipe = popen(limited.c_str(), "r");
  if (!pipe) return result;
  std::array<char, 4096> buffer{};
  while (fgets(buffer.data(), buffer.size(), pipe)) result.output += buffer.data();
  const int status = pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

std::filesystem::path bin_dir() {
  return COSIM_BIN_DIR;
}

CommandResult run_cosim(const std::string& arguments, int time_limit_seconds) {
  return run_command(fmt::format("{}/cosim {}", COSIM_BIN_DIR, arguments), time_limit_seconds);
}

CommandResult interrupt_cosim(const std::string& arguments, int seconds, int time_limit_seconds) {
  return run_command(
      fmt::format("sh -c '{}/cosim {} & pid=$!; sleep {}; kill -INT $pid; wait $pid'",
                  COSIM_BIN_DIR, arguments, seconds),
      time_limit_seconds);
}

std::filesystem::path run_folder_of(const CommandResult& result) {
  static const std::regex line("run folder: (\\S+)");
  std::smatch match;
  if (std::regex_search(result.output, match, line)) return match[1].str();
  return {};
}

nlohmann::json read_summary(const std::filesystem::path& run_dir) {
  std::ifstream in(run_dir / "summary.json");
  if (!in) return nlohmann::json::object();
  return nlohmann::json::parse(in);
}

std::filesystem::path fresh_folder(const std::string& name) {
  const auto folder =
      std::filesystem::temp_directory_path() / fmt::format("cosim-test-{}-{}", name, getpid());
  std::filesystem::remove_all(folder);
  std::filesystem::create_directories(folder);
  return folder;
}

std::filesystem::path test_scene(const std::string& name) {
  return std::filesystem::path(COSIM_TEST_SCENES) / name;
}

}  // namespace cosim::testing
