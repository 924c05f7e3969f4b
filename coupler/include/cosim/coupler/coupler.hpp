// The coupler: runs the windows of a scene in lockstep with every participant, rebroadcasting
// until each answers, and stops the run with a named culprit when a participant fails, dies or
// falls silent. It never does physics: it only orders, waits, records and reports.
#pragma once

#include <chrono>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "cosim/coupler/bus.hpp"
#include "cosim/coupler/checkpoints.hpp"
#include "cosim/coupler/process_group.hpp"
#include "cosim/scenario/scene.hpp"

namespace cosim::coupler {

struct CouplerOptions {
  std::string url;
  int64_t run_id = 0;
  std::filesystem::path event_log;  // every message heard is recorded here
  RecordMode record_mode = RecordMode::all;
  double loss_probability = 0.0;
  double startup_timeout = 60.0;  // seconds for every participant to become ready
  CheckpointOptions checkpoints;
  std::optional<RestartPoint> restart;  // continue after this window (participants restored)
};

struct ParticipantReport {
  std::string name;
  double compute_seconds = 0.0;  // wall time outside waiting for partners
  double cpu_seconds = 0.0;      // CPU time of the process, all threads
  double wait_seconds = 0.0;
  // Wall time the participant spent outside the participant API in windows 1..N: its physics
  // (and its output), the part of the run that is not coupling.
  double physics_seconds = 0.0;
  double physics_at_window_zero = -1.0;
  int64_t windows = 0;
  int64_t steps = 0;         // solver steps (sub-steps for sub-cycling solids), summed over windows
  std::string metrics_json;  // the participant's final report
};

struct RunResult {
  bool ok = false;
  std::string failure;  // names the participant and the window when !ok
  int64_t windows_completed = 0;
  int64_t total_windows = 0;
  double simulated_time = 0.0;
  double wall_seconds = 0.0;
  double coupler_wait_seconds = 0.0;
  // Wall time of windows 1..N, and the part of it no participant's physics explains: in the
  // serial scheme the participants' physics add up along the window, in the parallel one the
  // slowest participant's does. The rest is coupling: messages, waiting, retransmission.
  double windows_wall_seconds = 0.0;
  double critical_physics_seconds = 0.0;
  double overhead_seconds = 0.0;
  double overhead_fraction = 0.0;
  double overhead_ms_per_window = 0.0;
  std::vector<ParticipantReport> participants;
  Bus::Counters traffic;
  nlohmann::json checkpoints = nlohmann::json::array();  // CheckpointBook::written()
  // Implicit schemes: coupling iterations of every window 1..N (empty for explicit schemes),
  // and the windows that reached coupling.implicit.max_iterations without converging.
  std::vector<int> iterations;
  int64_t windows_at_max_iterations = 0;
  std::string acceleration;
  int64_t aitken_restarts = 0;  // coupling.implicit.positive_aitken: factors set back
  // Every iteration's convergence measure, as preCICE's convergence log: each exchanged field's
  // residual |H(x) - x| over its tolerance (<= 1: converged), fields named "drag of
  // vegetation_beam" in `convergence_fields`' order. summary.json's neighbour
  // implicit_convergence.csv holds it.
  struct IterationMeasure {
    int64_t window = 0;
    double time = 0.0;  // window start [s]
    int32_t iteration = 0;
    std::vector<double> ratios;
  };
  std::vector<std::string> convergence_fields;
  std::vector<IterationMeasure> convergence;
};

class Coupler {
 public:
  Coupler(const scenario::Scene& scene, CouplerOptions options);
  // Runs the scene with participants already started in `processes`.
  RunResult run(ProcessGroup& processes);

 private:
  struct Failure : std::runtime_error {
    using std::runtime_error::runtime_error;
  };
  // One round of the lockstep: broadcast `command` until every participant answers `answer`
  // (for this window when the answer is DONE); a failure, exit or silence ends the run.
  struct Collection {
    Stamp stamp;
    int8_t command = 0;
    int8_t answer = 0;
    std::string during;         // "window 5 (t = ...)", for exits and silence
    std::string failed_during;  // "in window 5 (t = ...)", for reported failures
    bool patient = false;       // rebroadcast slowly after a while (long initialisations)
    std::function<void(const cosim_msgs::status_t&)> accept;
    std::function<void(const std::vector<std::string>& pending, double waited)> check;
    // Replaces the plain broadcast of `command` (an implicit iteration's grant).
    std::function<void()> broadcast;
    // Called when the run is interrupted (SIGINT/SIGTERM) during the collection, before it stops:
    // an implicit window's chance to save the state after the last accepted window.
    std::function<void()> on_interrupt;
  };
  void collect(ProcessGroup& processes, const Collection& collection);
  void handshake(ProcessGroup& processes);
  // Windows 0..N: grants windows ahead so participants never wait for the coupler (an adaptive
  // window as soon as the participants that limit it have reported the one before), collects
  // every DONE, and returns the simulated time reached.
  double run_windows(ProcessGroup& processes, RunResult& result);
  // The same for the implicit schemes: one iteration of one window granted at a time, each
  // window iterated until the exchanged fields converge (coupler/src/coupler_implicit.cpp).
  double run_implicit_windows(ProcessGroup& processes, RunResult& result);
  class ImplicitWindows;  // that loop's state and stages (coupler_implicit.cpp)
  // Both window loops (coupler.cpp, coupler_implicit.cpp):
  // plan_ from window 0, or from a restart's window N (its start time), which it returns.
  double start_plan();
  // Appends window plan_.size() to plan_, starting at next_time (advanced): the scene's window,
  // shortened when adaptive to the smallest stable dt reported for the window before, landing on
  // the duration. False, planning nothing, once the duration is reached.
  bool plan_next_window(double& next_time, const std::map<int64_t, double>& stable_dt,
                        RunResult& result);
  // summary.json's coupling_overhead: the wall time of windows 1..completed (from
  // `windows_started`) minus the participants' physics (summed along a serial chain).
  void book_overhead(RunResult& result, std::chrono::steady_clock::time_point windows_started,
                     int64_t completed, bool serial) const;

  // The explicit window loop's record of the participants' reports.
  struct Progress {
    std::map<std::string, int64_t> done;  // highest window each participant finished, in order
    std::map<std::string, std::map<int64_t, cosim_msgs::status_t>> early;  // heard out of order
    std::map<int64_t, double> stable_dt;  // smallest stable dt reported per window
    int64_t completed = -1;               // every participant has finished it
    int64_t granted = -1;
  };
  // Takes every report the bus holds into `progress`; true when some participant finished a
  // window. A FAILED report stops the run.
  bool take_reports(Progress& progress);
  // A participant's process ended: its last reports are taken, an interrupted run saves the
  // state after the last window granted, and the run stops naming the window.
  [[noreturn]] void stop_on_exit(ProcessGroup& processes, const ChildExit& exit, Progress& progress,
                                 int64_t first, RunResult& result);

  // A DONE report into reports_ (steps, times; a window when new_window) and the smallest
  // stable dt of its window into stable_dt.
  void book_report(const cosim_msgs::status_t& status, bool new_window,
                   std::map<int64_t, double>& stable_dt);
  std::string window_text(int64_t index) const;
  void finish(ProcessGroup& processes, int64_t index, double time);
  void check_processes(ProcessGroup& processes, const std::string& during);
  void check_silence(const std::vector<std::string>& pending, const std::string& during);
  // Start of window index + 1 as planned: where a checkpoint after `index` stands in time.
  double end_of(int64_t index) const;
  // Waits until every requested checkpoint is written (asking again with COMMAND_CHECKPOINT).
  // interrupted: give up quietly on a participant that fails or falls silent.
  void await_checkpoints(ProcessGroup& processes, int64_t granted, bool interrupted);

  const scenario::Scene& scene_;
  CouplerOptions options_;
  std::unique_ptr<Bus> bus_;
  std::vector<std::string> names_;  // acts_as names of the participants
  // Those that declared at the handshake that their stable dt may shorten a window.
  std::set<std::string> limiting_;
  std::map<std::string, ParticipantReport> reports_;
  std::vector<std::pair<double, double>> plan_;  // (start, length) of window i, once known
  std::chrono::steady_clock::time_point started_;
  CheckpointBook book_;
};

}  // namespace cosim::coupler
