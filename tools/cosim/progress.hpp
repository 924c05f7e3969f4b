// Progress of a running scene: window k of N, simulated time, wall time and an estimate of the
// time left. It listens to the coupler's window broadcasts on the run's LCM URL from a thread
// of its own, so the coupler itself is untouched. On a terminal one line is redrawn every
// second; anywhere else (a pipe, a log file) it prints plain lines every `interval` seconds.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

namespace cosim::tool {

// Human-readable duration: "8.2 s", "3 min 05 s", "2 h 07 min".
std::string format_duration(double seconds);

// What one progress line says.
struct ProgressState {
  std::string scene;
  int64_t window = 0;  // the window being computed (windows before it are done)
  int64_t total_windows = 0;
  double simulated = 0.0;  // simulated time reached [s]
  double duration = 0.0;   // the scene's duration [s]
  double wall = 0.0;       // wall seconds since the run started
  // Wall seconds since window 1 started and the simulated time then: the rate of the ETA
  // leaves the start-up (packing, first handshake) out.
  double stepping_wall = 0.0;
  double stepping_from = 0.0;
  bool started = false;  // window 1 has begun
};

// Estimated wall seconds left, or nothing before there is a rate to go by.
std::optional<double> estimate_remaining(const ProgressState& state);
std::string progress_line(const ProgressState& state);

class ProgressMonitor {
 public:
  struct Options {
    std::string url;  // the run's LCM URL
    int64_t run_id = 0;
    std::string scene;
    double duration = 0.0;
    int64_t total_windows = 0;
    double interval = 0.0;  // seconds between lines; 0: 1 s on a terminal, 10 s otherwise
    std::FILE* out = stderr;
  };
  explicit ProgressMonitor(Options options);
  ~ProgressMonitor();
  ProgressMonitor(const ProgressMonitor&) = delete;
  ProgressMonitor& operator=(const ProgressMonitor&) = delete;

  // Stops listening and prints the closing line with the run's outcome.
  void finish(bool ok, int64_t windows_completed, double simulated_time, double wall_seconds);

 private:
  void listen();
  void print();

  Options options_;
  bool terminal_ = false;
  std::chrono::steady_clock::time_point started_;
  std::chrono::steady_clock::time_point last_print_;
  std::chrono::steady_clock::time_point stepping_started_;
  std::mutex mutex_;
  ProgressState state_;
  bool printed_any_ = false;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace cosim::tool
