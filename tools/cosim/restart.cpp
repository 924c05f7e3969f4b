#include "restart.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <yaml-cpp/yaml.h>

#include <bit>
#include <cmath>
#include <fstream>
#include <stdexcept>

#include "cosim/checkpoint/archive.hpp"
#include "cosim_msgs/header_t.hpp"
#include "cosim_version.hpp"

namespace cosim::tool {

namespace {

[[noreturn]] void refuse(const std::filesystem::path& file, const std::string& problem) {
  throw std::runtime_error(fmt::format("--restart: {}: {}", file.string(), problem));
}

nlohmann::json read_manifest(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) refuse(file, "missing: the checkpoint is incomplete");
  auto manifest = nlohmann::json::parse(in, nullptr, false);
  if (!manifest.is_object()) refuse(file, "damaged manifest (not a JSON object)");
  for (const char* key : {"schema_version", "scene", "scenario_hash", "window", "time"}) {
    if (!manifest.contains(key)) refuse(file, fmt::format("damaged manifest: no '{}'", key));
  }
  return manifest;
}

// Complete checkpoints of a run (those with a manifest), oldest first.
std::vector<std::filesystem::path> checkpoint_folders(const std::filesystem::path& run_dir) {
  std::vector<std::filesystem::path> folders;
  const auto root = run_dir / "checkpoints";
  if (!std::filesystem::is_directory(root)) return folders;
  for (const auto& entry : std::filesystem::directory_iterator(root)) {
    if (entry.is_directory() && entry.path().filename().string().starts_with("window_") &&
        std::filesystem::exists(entry.path() / "manifest.json")) {
      folders.push_back(entry.path());
    }
  }
  std::sort(folders.begin(), folders.end());  // window_NNNNNNNN: name order is window order
  return folders;
}

double manifest_time(const nlohmann::json& manifest) {
  if (manifest.contains("time_bits")) {
    return std::bit_cast<double>(
        std::stoull(manifest["time_bits"].get<std::string>(), nullptr, 16));
  }
  return manifest["time"].get<double>();
}

std::filesystem::path choose(const scenario::Scene& scene, const RestartSource& source) {
  const auto folders = checkpoint_folders(source.run_dir);
  if (folders.empty()) {
    refuse(source.run_dir / "checkpoints",
           "the run has no complete checkpoint (no window_*/manifest.json)");
  }
  if (!source.time) return folders.back();
  std::vector<std::string> times;
  for (const auto& folder : folders) {
    const double time = manifest_time(read_manifest(folder / "manifest.json"));
    // Within half a window: the time as printed in summary.json or typed by hand.
    if (std::abs(time - *source.time) <= 0.5 * scene.coupling.window) return folder;
    times.push_back(fmt::format("{:.9g}", time));
  }
  refuse(source.run_dir / "checkpoints",
         fmt::format("no checkpoint at t = {:.9g} s (there are checkpoints at t = {} s)",
                     *source.time, fmt::join(times, ", ")));
}

void check_files(const scenario::Scene& scene, const std::filesystem::path& folder,
                 const nlohmann::json& manifest, const std::filesystem::path& manifest_file) {
  const auto& files = manifest.contains("participants") ? manifest["participants"] : manifest;
  if (!files.is_array()) refuse(manifest_file, "damaged manifest: no list of 'participants'");
  for (const auto& entry : scene.participants) {
    const nlohmann::json* listed = nullptr;
    for (const auto& file : files) {
      if (file.is_object() && file.value("name", "") == entry.name) listed = &file;
    }
    if (!listed) {
      refuse(manifest_file, fmt::format("holds no state of participant '{}'", entry.name));
    }
    const auto file = folder / listed->value("file", entry.name + ".ckpt");
    checkpoint::FileInfo info;
    try {
      info = checkpoint::verify(file);
    } catch (const checkpoint::Error& error) {
      throw std::runtime_error(std::string("--restart: ") + error.what());
    }
    if (info.kind != entry.executable) {
      refuse(file, fmt::format("a checkpoint of '{}', where the scene runs '{}' as '{}'", info.kind,
                               entry.executable, entry.name));
    }
    if (info.bytes != listed->value("bytes", uint64_t{0})) {
      refuse(file, fmt::format("{} bytes where the manifest lists {} (replaced or cut?)",
                               info.bytes, listed->value("bytes", uint64_t{0})));
    }
  }
}

}  // namespace

RestartSource parse_restart(const std::string& text) {
  RestartSource source{text, std::nullopt};
  if (const auto at = text.rfind('@'); at != std::string::npos && at + 1 < text.size()) {
    std::size_t used = 0;
    try {
      const double time = std::stod(text.substr(at + 1), &used);
      if (used == text.size() - at - 1 && std::isfinite(time)) {
        source.run_dir = text.substr(0, at);
        source.time = time;
      }
    } catch (const std::exception&) {
    }
  }
  if (!std::filesystem::is_directory(source.run_dir)) {
    throw std::runtime_error(
        fmt::format("--restart: {}: no such run folder", source.run_dir.string()));
  }
  return source;
}

std::string scenario_hash(const scenario::Scene& scene) {
  YAML::Node resolved = YAML::Clone(scene.resolved);
  resolved.remove("duration");
  resolved.remove("checkpoint_interval");
  YAML::Emitter emitter;
  emitter << resolved;
  // FNV-1a, 64 bits: a fingerprint, not a defence against forgery.
  uint64_t hash = 1469598103934665603ULL;
  for (const char c : std::string(emitter.c_str())) {
    hash = (hash ^ static_cast<unsigned char>(c)) * 1099511628211ULL;
  }
  return fmt::format("{:016x}", hash);
}

nlohmann::json manifest_base(const scenario::Scene& scene) {
  return {{"scene", scene.name},
          {"scenario", scene.file.string()},
          {"scenario_hash", scenario_hash(scene)},
          {"build", kVersion},
          {"protocol_schema_hash",
           fmt::format("{:016x}", static_cast<uint64_t>(cosim_msgs::header_t::getHash()))},
          {"file_format_version", checkpoint::kFormatVersion}};
}

ResolvedRestart resolve_restart(const scenario::Scene& scene, const RestartSource& source) {
  ResolvedRestart restart;
  restart.folder = choose(scene, source);
  const auto manifest_file = restart.folder / "manifest.json";
  restart.manifest = read_manifest(manifest_file);
  const auto& m = restart.manifest;
  if (m["schema_version"] != coupler::kCheckpointSchemaVersion) {
    refuse(manifest_file, fmt::format("checkpoint schema version {} (build {}), where this build "
                                      "({}) reads version {}",
                                      m["schema_version"].dump(), m.value("build", "?"), kVersion,
                                      coupler::kCheckpointSchemaVersion));
  }
  if (m["scene"] != scene.name) {
    refuse(manifest_file,
           fmt::format("a checkpoint of scene '{}', not of '{}' ({})",
                       m["scene"].get<std::string>(), scene.name, scene.file.string()));
  }
  if (m["scenario_hash"] != scenario_hash(scene)) {
    refuse(manifest_file,
           fmt::format("written for other settings of scene '{}' (scenario hash {}, this "
                       "scenario {}); only duration and checkpoint_interval may change",
                       scene.name, m["scenario_hash"].get<std::string>(), scenario_hash(scene)));
  }
  restart.point.window = m["window"].get<int64_t>();
  restart.point.time = manifest_time(m);
  if (restart.point.window < 1 || !(restart.point.time < scene.duration)) {
    refuse(manifest_file,
           fmt::format("nothing left to run: the checkpoint is at t = {:.9g} s and the scene "
                       "ends at {:.9g} s (raise duration, e.g. --set duration=...)",
                       restart.point.time, scene.duration));
  }
  check_files(scene, restart.folder, m, manifest_file);
  return restart;
}

}  // namespace cosim::tool
