// Running a scene: the run folder, the processes, the coupler, and the summary.
#pragma once

#include <filesystem>
#include <map>
#include <string>

#include "cosim/coupler/coupler.hpp"
#include "cosim/scenario/scene.hpp"

namespace cosim::tool {

// Checks every participant section a scene may hold (one parser per participant kind).
const std::map<std::string, scenario::ParticipantParser>& participant_parsers();

struct RunRequest {
  std::filesystem::path runs_dir = "runs";
  std::string run_label;                      // appended to the scene name in the run folder's name
  double loss_probability = 0.0;              // injected loss of received messages, every process
  coupler::RecordMode record_mode = coupler::RecordMode::all;  // what events.lcmlog keeps
  std::map<std::string, std::string> faults;  // participant -> "exit@W" / "hang@W" / "throw@W"
  bool show_progress = true;
  double progress_interval =
      0.0;  // seconds between progress lines; 0: 1 s on a terminal, else 10 s
};

struct RunOutcome {
  std::filesystem::path run_dir;
  coupler::RunResult result;
  int exit_code = 0;  // 0 ok, 1 the run failed
};

RunOutcome run_scene(const scenario::Scene& scene, const RunRequest& request);

// Prints the metrics of a finished run against their references, with run times.
void print_report(const std::filesystem::path& run_dir);

}  // namespace cosim::tool
