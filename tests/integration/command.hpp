// Running `cosim` from tests: output captured, exit code and wall time measured.
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

namespace cosim::testing {

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr
  double seconds = 0.0;
};

// Runs a shell command (with a hard time limit, so a hang fails the test instead of blocking it).
CommandResult run_command(const std::string& command, int time_limit_seconds = 120);

// The build's bin folder (cosim and the solvers).
std::filesystem::path bin_dir();

// `cosim` with arguments, from the build's bin folder.
CommandResult run_cosim(const std::string& arguments, int time_limit_seconds = 120);

// `cosim` with arguments, sent SIGINT after `seconds` (as a user's Ctrl-C); waits for it to end.
CommandResult interrupt_cosim(const std::string& arguments, int seconds,
                              int time_limit_seconds = 300);

// The run folder a `cosim run` printed, or empty.
std::filesystem::path run_folder_of(const CommandResult& result);

nlohmann::json read_summary(const std::filesystem::path& run_dir);

// A fresh folder for one test's runs.
std::filesystem::path fresh_folder(const std::string& name);

std::filesystem::path test_scene(const std::string& name);

#ifdef COSIM_SCENARIOS
// A bundle of scenarios/ (the test target defines COSIM_SCENARIOS as that folder).
inline std::string scenario(const std::string& name) {
  return (std::filesystem::path(COSIM_SCENARIOS) / name).string();
}
#endif

// The `report.metrics` of the first participant in a summary.json.
inline const nlohmann::json& metrics_of(const nlohmann::json& summary) {
  return summary["participants"][0]["report"]["metrics"];
}

// The `report.info` of participant `name` in a summary.json; throws (failing the test) if none.
inline const nlohmann::json& info_of(const nlohmann::json& summary, const std::string& name) {
  for (const auto& p : summary["participants"]) {
    if (p["name"] == name) return p["report"]["info"];
  }
  throw std::out_of_range("summary.json has no participant " + name);
}

// A JSON array of three numbers (an impulse in summary.json) as a vector.
inline Eigen::Vector3d vector_of(const nlohmann::json& values) {
  return {values[0].get<double>(), values[1].get<double>(), values[2].get<double>()};
}

// The world impulses [N s] a flow reports for the solids' reaction (its summary info).
struct FlowImpulses {
  Eigen::Vector3d booked;        // handed over by the link, in the flow's plane
  Eigen::Vector3d received;      // taken by fluid particles
  Eigen::Vector3d undelivered;   // no fluid near the solid point
  Eigen::Vector3d out_of_plane;  // no place in a 2D flow
};
inline FlowImpulses flow_impulses(const nlohmann::json& info) {
  return {vector_of(info["booked_solid_reaction_impulse"]),
          vector_of(info["solid_reaction_impulse"]),
          vector_of(info["undelivered_solid_force_impulse"]),
          vector_of(info["out_of_plane_solid_force_impulse"])};
}

}  // namespace cosim::testing
