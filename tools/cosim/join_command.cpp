#include "join_command.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "cosim/coupler/process_group.hpp"
#include "cosim/coupler/process_main.hpp"
#include "network.hpp"
#include "sweep.hpp"
#include "thread_wait.hpp"

namespace cosim::tool {

void join_run(const JoinRequest& request) {
  const auto scene = load_with_overrides(request.scenario, {});
  const auto* entry = find_participant(scene, request.name);
  if (!entry) {
    throw std::invalid_argument(fmt::format("--name '{}' ({}): {}", request.name,
                                            request.scenario.string(),
                                            no_participant(scene, request.name)));
  }
  if (request.url.rfind("udpm://", 0) != 0 || request.url.find("ttl=0") != std::string::npos) {
    throw std::invalid_argument(fmt::format(
        "--lcm-url '{}': a run reachable from another host has a udpm:// URL with ttl of 1 or "
        "more (the one `cosim run --remote` printed)",
        request.url));
  }
  if (!multicast_available()) {
    throw std::runtime_error(
        "this host has no multicast route, so LCM cannot reach the run: add one on the "
        "interface that leads to the coupler's host, e.g. `ip route add 224.0.0.0/4 dev eth0`");
  }
  const auto executable = coupler::executable_dir() / entry->executable;
  if (!std::filesystem::exists(executable)) {
    throw std::runtime_error(
        fmt::format("the solver '{}' is not built on this host: {} does not "
                    "exist",
                    entry->executable, executable.string()));
  }
  std::filesystem::create_directories(request.run_dir);
  auto words = coupler::process_arguments(executable, request.scenario, request.run_dir,
                                          request.name, request.url, request.run_id, 0.0, "");
  std::vector<char*> arguments;
  for (auto& word : words) arguments.push_back(word.data());
  arguments.push_back(nullptr);
  set_thread_wait();  // as `cosim run` does for the processes it starts
  execv(arguments[0], arguments.data());
  throw std::runtime_error(
      fmt::format("cannot start {}: {}", executable.string(), std::strerror(errno)));
}

CLI::App* add_join_command(CLI::App& app, JoinRequest& request) {
  auto* command = app.add_subcommand(
      "join",
      "start one participant of a run whose coupler is on another host (the line "
      "`cosim run --remote NAME` prints)");
  command->add_option("--scenario", request.scenario, "the run's resolved scenario.yaml")
      ->required()
      ->check(CLI::ExistingFile);
  command->add_option("--run-dir", request.run_dir, "where this participant writes its outputs")
      ->required();
  command->add_option("--name", request.name, "the participant")->required();
  command->add_option("--lcm-url", request.url, "the run's LCM URL")->required();
  command->add_option("--run-id", request.run_id, "the run's id")->required();
  return command;
}

}  // namespace cosim::tool
