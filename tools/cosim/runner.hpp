// Running a scene: the run folder, the processes, the coupler, and the summary.
#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "cosim/coupler/coupler.hpp"
#include "cosim/scenario/scene.hpp"
#include "restart.hpp"

namespace cosim::tool {

// Checks every participant section a scene may hold (one parser per participant kind).
const std::map<std::string, scenario::ParticipantParser>& participant_parsers();

struct RunRequest {
  std::filesystem::path runs_dir = "runs";
  std::string run_label;          // appended to the scene name in the run folder's name
  double loss_probability = 0.0;  // injected loss of received messages, every process
  coupler::RecordMode record_mode = coupler::RecordMode::all;  // what events.lcmlog keeps
  std::map<std::string, std::string> faults;  // participant -> "exit@W" / "hang@W" / "throw@W"
  // Continue from a coupled checkpoint of an earlier run (checked before anything starts).
  std::optional<RestartSource> restart;
  // Participants started by hand on other hosts (`cosim join`), not by this command; the run's
  // multicast then leaves this host with time-to-live `lcm_ttl`.
  std::vector<std::string> remote;
  int lcm_ttl = 1;
  double startup_timeout = 0.0;  // s for every participant to start; 0: 60, or 600 with remote
  bool show_progress = true;
  double progress_interval =
      0.0;  // seconds between progress lines; 0: 1 s on a terminal, else 10 s
};

struct RunOutcome {
  std::filesystem::path run_dir;
  coupler::RunResult result;
  int exit_code = 0;       // 0 ok, 1 the run failed, 128 + signal when interrupted
  int interrupted_by = 0;  // SIGINT or SIGTERM when the run was interrupted, else 0
};

// The scene's participant whose section is `name`, or nullptr; and the words for its absence,
// "this scene runs no participant 'x' (it runs a, b)".
const scenario::ParticipantEntry* find_participant(const scenario::Scene& scene,
                                                   const std::string& name);
std::string no_participant(const scenario::Scene& scene, const std::string& name);

// The fault kinds a participant process can inject (coupler/process_main.cpp).
const std::vector<std::string>& fault_kinds();

// Checks what the command line asks of a run against the scene, before anything is made or
// started: every --fault names a participant of the scene, a known kind and a window 1..N;
// the injected loss is a finite fraction in [0, 0.5]; every --remote names a participant once,
// without a fault. Throws std::invalid_argument naming the
// option and its value.
void check_run_request(const scenario::Scene& scene, const RunRequest& request);

// Runs the scene. SIGINT and SIGTERM during the run stop every child, write summary.json with
// ok: false and the reason, and give exit code 128 + signal.
RunOutcome run_scene(const scenario::Scene& scene, const RunRequest& request);

// One line for an interrupted run: what stopped it, where, and the run folder.
std::string interruption_line(const RunOutcome& outcome);

// Prints the metrics of a finished run against their references, with run times.
void print_report(const std::filesystem::path& run_dir);

}  // namespace cosim::tool
