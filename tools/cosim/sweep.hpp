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

// `cosim spread`: the bundle as it is, then once per perturbation, a KEY=VALUE that should change
// nothing physical (a tighter solver tolerance, a slightly other step, another order of the same
// sums). How far each metric moves over these runs is the noise that a difference between two
// variants of the scene has to exceed before it says anything.
struct SpreadRequest {
  std::filesystem::path bundle;
  std::vector<std::string> overrides;      // KEY=VALUE applied to every run
  std::vector<std::string> perturbations;  // KEY=VALUE, one run each
  RunRequest run;
};

// Returns the exit code: 0 when every run succeeded.
int spread(const SpreadRequest& request);

// One row of a sweep: the value, the run and its metrics (as in summary.json).
struct SweepRow {
  std::string value;
  bool ok = false;
  double wall = 0;
  std::vector<std::pair<std::string, nlohmann::json>> metrics;
  std::filesystem::path run_dir;
};

// One metric over the runs of a spread (the first row is the bundle as it is): its value and,
// with a reference, its relative error (summary.json's, a fraction) in the base run and their
// smallest and largest over every run that reported it.
struct MetricSpread {
  std::string name;
  std::string unit;
  int runs = 0;
  double base_value = 0, min_value = 0, max_value = 0;
  bool has_error = false;
  double base_error = 0, min_error = 0, max_error = 0;
};
// Metrics in the order the base run reports them; a metric missing from the base run is left
// out (it has nothing to be compared with).
std::vector<MetricSpread> metric_spreads(const std::vector<SweepRow>& rows);

// The figure of a sweep: relative error against wall time, one curve per metric with an error
// (log-log, points named by the value); without any error, each metric's value against wall
// time. `file` is where the PNG goes.
nlohmann::json sweep_figure(const std::string& scene, const std::string& vary,
                            const std::vector<SweepRow>& rows, const std::filesystem::path& file);

}  // namespace cosim::tool
