// `cosim run <bundle> --restart <run folder>[@time]`: finding the coupled checkpoint to continue
// from and refusing one that does not fit, before any process starts.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "cosim/coupler/checkpoints.hpp"
#include "cosim/scenario/scene.hpp"

namespace cosim::tool {

struct RestartSource {
  std::filesystem::path run_dir;
  std::optional<double> time;  // the checkpoint at this time; none: the latest one
};

// "<run folder>" or "<run folder>@<time>" (the last '@' followed by a number).
RestartSource parse_restart(const std::string& text);

struct ResolvedRestart {
  std::filesystem::path folder;  // checkpoints/window_N of the run
  nlohmann::json manifest;
  coupler::RestartPoint point;
};

// Picks the checkpoint and checks it against the scene: the same scene and scenario (apart
// from duration and checkpoint_interval), the same checkpoint schema, a time before the scene's
// end, and every participant's file present, whole (checksum) and of the right kind. Throws
// std::runtime_error naming the file and the problem.
ResolvedRestart resolve_restart(const scenario::Scene& scene, const RestartSource& source);

// Hash of the resolved scenario without the keys a continued run may change (duration,
// checkpoint_interval): two runs with the same hash compute the same thing.
std::string scenario_hash(const scenario::Scene& scene);

// What every manifest of this run holds besides the window: scene, scenario hash, versions.
nlohmann::json manifest_base(const scenario::Scene& scene);

}  // namespace cosim::tool
