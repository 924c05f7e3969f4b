// What one participant said during a recorded run, read back from the run's LCM event log:
// its fields per window (chunks reassembled, retransmissions merged), its window reports and its
// final metrics. The replay stand-in plays this back; `cosim replay` compares against it.
#pragma once

#include <compare>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace cosim::replay {

// A window, and its coupling iteration (implicit schemes; 0 for the explicit ones).
struct WindowKey {
  int64_t window = 0;
  int32_t iteration = 0;
  auto operator<=>(const WindowKey&) const = default;
};
// "window 5", or "window 5, iteration 2" after the first iteration.
std::string describe(const WindowKey& key);

struct RecordedWindow {
  std::map<std::string, std::vector<double>> fields;
  bool done = false;
  int32_t steps = 0;
  double stable_dt = 0.0;
};

struct Recording {
  int64_t run_id = 0;
  std::string participant;
  std::map<WindowKey, RecordedWindow> windows;  // every iteration of every window
  std::string declaration;  // frame, dimension, span and gravity declared at the handshake
  bool finished = false;
  std::string metrics_json;
};

// Reads `participant`'s messages of the run recorded in `event_log` (the run id is the
// coupler's). Throws with the file name when the log is unreadable or a field is incomplete.
Recording read_recording(const std::filesystem::path& event_log, const std::string& participant);

// Names of every participant that published a field in the log.
std::vector<std::string> recorded_participants(const std::filesystem::path& event_log);

struct Mismatch {
  WindowKey window;
  std::string field;
  std::string problem;
};
// Every difference between two recordings' fields, compared bit for bit.
std::vector<Mismatch> compare_fields(const Recording& expected, const Recording& actual);

}  // namespace cosim::replay
