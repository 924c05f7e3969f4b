#include "cosim/coupler/checkpoints.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <bit>
#include <cmath>
#include <fstream>

namespace cosim::coupler {

CheckpointBook::CheckpointBook(CheckpointOptions options,
                               std::vector<std::pair<std::string, std::string>> participants)
    : options_(std::move(options)), participants_(std::move(participants)) {}

void CheckpointBook::plan(int64_t index, double start, double end) {
  if (!enabled() || !(options_.interval > 0.0) || index < 1) return;
  // Multiples of the interval, with the output clock's tolerance: no drift over long runs.
  const double interval = options_.interval;
  const double before = std::floor(start / interval + 1e-9);
  const double after = std::floor(end / interval + 1e-9);
  if (after > before) requests_.emplace(index, end);
}

void CheckpointBook::request(int64_t index, double end) {
  if (enabled() && index >= 1 && !complete(index)) requests_.emplace(index, end);
}

std::vector<int64_t> CheckpointBook::pending(int64_t granted) const {
  std::vector<int64_t> windows;
  for (const auto& [index, end] : requests_) {
    if (index <= granted) windows.push_back(index);
  }
  return windows;
}

void CheckpointBook::answer(const cosim_msgs::status_t& status) {
  const int64_t index = status.header.window;
  if (!requests_.contains(index)) return;
  auto& answers = answers_[index];
  answers[status.header.sender] = nlohmann::json::parse(status.message, nullptr, false);
  if (answers.size() < participants_.size()) return;
  for (const auto& [acts_as, name] : participants_) {
    if (!answers.contains(acts_as)) return;
  }
  write_manifest(index);
}

std::vector<std::string> CheckpointBook::waiting_for() const {
  std::vector<std::string> names;
  if (requests_.empty()) return names;
  const auto found = answers_.find(requests_.begin()->first);
  for (const auto& [acts_as, name] : participants_) {
    if (found == answers_.end() || !found->second.contains(acts_as)) names.push_back(acts_as);
  }
  return names;
}

void CheckpointBook::write_manifest(int64_t index) {
  const double end = requests_.at(index);
  const auto folder = options_.folder / fmt::format("window_{:08d}", index);
  nlohmann::json manifest = options_.manifest;
  manifest["schema_version"] = kCheckpointSchemaVersion;
  manifest["window"] = index;
  manifest["time"] = end;
  // Bit for bit: the time is where the restarted coupler plans window index + 1 from.
  manifest["time_bits"] = fmt::format("{:016x}", std::bit_cast<uint64_t>(end));
  nlohmann::json files = nlohmann::json::array();
  uint64_t bytes = 0;
  double slowest = 0.0;
  for (const auto& [acts_as, name] : participants_) {
    const auto& answer = answers_[index][acts_as];
    files.push_back({{"name", name},
                     {"acts_as", acts_as},
                     {"file", answer.value("file", "")},
                     {"bytes", answer.value("bytes", uint64_t{0})},
                     {"write_seconds", answer.value("write_seconds", 0.0)}});
    bytes += answer.value("bytes", uint64_t{0});
    slowest = std::max(slowest, answer.value("write_seconds", 0.0));
  }
  manifest["participants"] = files;
  const auto file = folder / "manifest.json";
  auto temporary = file;
  temporary += ".part";
  {
    std::ofstream out(temporary, std::ios::trunc);
    out << manifest.dump(2) << '\n';
    if (!out.flush()) {
      spdlog::error("{}: cannot write the checkpoint manifest", file.string());
      requests_.erase(index);
      return;
    }
  }
  std::filesystem::rename(temporary, file);
  requests_.erase(index);
  answers_.erase(index);
  written_indices_.insert(index);
  written_.push_back({{"window", index},
                      {"time", end},
                      {"folder", folder.string()},
                      {"bytes", bytes},
                      {"write_seconds", slowest}});
  spdlog::info("checkpoint after window {} (t = {:.9g} s): {} ({} bytes)", index, end,
               folder.string(), bytes);
}

}  // namespace cosim::coupler
