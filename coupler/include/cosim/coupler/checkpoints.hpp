// The coupler's side of coupled checkpoints: which windows end with one (every
// `checkpoint_interval` of simulated time, and the last granted window when the run is
// interrupted), the participants' answers, and the manifest written once every participant's
// file is there. The files themselves are written by each process (run_solver_loop).
//
// A checkpoint is the folder <run>/checkpoints/window_NNNNNNNN/ holding one <name>.ckpt per
// participant and manifest.json (scene, scenario hash, schema and build versions, window, time,
// the coupler's own state and the files with their sizes). A folder without a manifest is
// incomplete and never used.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "cosim_msgs/status_t.hpp"

namespace cosim::coupler {

// Version of the manifest and of what a checkpoint holds; a restart refuses another one.
inline constexpr int kCheckpointSchemaVersion = 1;

struct CheckpointOptions {
  std::filesystem::path folder;  // <run>/checkpoints; empty: no checkpoints at all
  double interval = 0.0;         // simulated seconds between checkpoints; 0: on interruption only
  nlohmann::json manifest;       // scene, scenario hash, build...: copied into every manifest
};

// Where a restarted run starts: after window `window`, at time `time` (the start of window
// window + 1 as the coupler planned it).
struct RestartPoint {
  int64_t window = 0;
  double time = 0.0;
};

class CheckpointBook {
 public:
  // participants: (acts_as, section name) of every participant.
  CheckpointBook(CheckpointOptions options,
                 std::vector<std::pair<std::string, std::string>> participants);

  bool enabled() const { return !options_.folder.empty(); }
  // Window `index` was planned to end at `end`: a checkpoint follows it when it crosses a
  // multiple of the interval.
  void plan(int64_t index, double start, double end);
  // A checkpoint after `index` (ending at `end`) now: the run is being interrupted.
  void request(int64_t index, double end);
  // Requested checkpoints not yet complete, up to window `granted`: they go with every grant.
  std::vector<int64_t> pending(int64_t granted) const;
  bool outstanding() const { return !requests_.empty(); }
  void forget_after(int64_t granted) {
    requests_.erase(requests_.upper_bound(granted), requests_.end());
  }
  bool complete(int64_t index) const { return written_indices_.contains(index); }
  // A participant's STATE_CHECKPOINTED; the manifest is written when the last one arrives.
  void answer(const cosim_msgs::status_t& status);
  // Participants that have not answered for the oldest outstanding checkpoint.
  std::vector<std::string> waiting_for() const;
  // One entry per complete checkpoint: window, time, folder, bytes, slowest write [s].
  const nlohmann::json& written() const { return written_; }

 private:
  void write_manifest(int64_t index);

  CheckpointOptions options_;
  std::vector<std::pair<std::string, std::string>> participants_;
  std::map<int64_t, double> requests_;  // window -> end time
  std::map<int64_t, std::map<std::string, nlohmann::json>> answers_;
  std::set<int64_t> written_indices_;
  nlohmann::json written_ = nlohmann::json::array();
};

}  // namespace cosim::coupler
