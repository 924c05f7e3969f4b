// `cosim sweep`: runs a scene once per value of one parameter (typically the resolution) and
// tabulates every metric against the run time: the error-versus-cost table of a scene.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "runner.hpp"

namespace cosim::tool {

struct SweepRequest {
  std::filesystem::path bundle;
  std::vector<std::string> overrides;  // KEY=VALUE applied to every run
  std::string vary;                    // dotted key
  std::vector<std::string> values;
  RunRequest run;
  bool plot = true;  // the error-vs-run-time figure beside the CSV (needs matplotlib)
};

// Loads a bundle's scenario with KEY=VALUE overrides and checks it.
scenario::Scene load_with_overrides(const std::filesystem::path& bundle,
                                    const std::vector<std::string>& overrides);

// Returns the exit code: 0 when every run succeeded and the figure was drawn.
int sweep(const SweepRequest& request);

// One row of a sweep: the value, the run and its metrics (as in summary.json).
struct SweepRow {
  std::string value;
  bool ok = false;
  double wall = 0;
  std::vector<std::pair<std::string, nlohmann::json>> metrics;
  std::filesystem::path run_dir;
};

// The figure of a sweep: relative error against wall time, one curve per metric with an error
// (log-log, points named by the value); without any error, each metric's value against wall
// time. `file` is where the PNG goes.
nlohmann::json sweep_figure(const std::string& scene, const std::string& vary,
                            const std::vector<SweepRow>& rows, const std::filesystem::path& file);

}  // namespace cosim::tool
