// `cosim join`: starts one participant of a run whose coupler runs on another host
// (`cosim run --remote NAME` prints the exact line). The solver process is this host's build,
// found beside this `cosim`; it reaches the run over the multicast address in --lcm-url.
#pragma once

#include <CLI/CLI.hpp>

#include <cstdint>
#include <filesystem>
#include <string>

namespace cosim::tool {

struct JoinRequest {
  std::filesystem::path scenario;  // the run's resolved scenario.yaml, copied to this host
  std::filesystem::path run_dir;   // where this participant writes its outputs and log
  std::string name;                // the participant's section name in the scenario
  std::string url;                 // the run's LCM URL
  int64_t run_id = 0;
};

// Replaces this process with the participant's solver. Returns only on failure (throws).
[[noreturn]] void join_run(const JoinRequest& request);

CLI::App* add_join_command(CLI::App& app, JoinRequest& request);

}  // namespace cosim::tool
