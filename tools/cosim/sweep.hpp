// `cosim sweep`: runs a scene once per value of one parameter (typically the resolution) and
// tabulates every metric against the run time: the error-versus-cost table of a scene.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "runner.hpp"

namespace cosim::tool {

struct SweepRequest {
  std::filesystem::path bundle;
  std::vector<std::string> overrides;  // KEY=VALUE applied to every run
  std::string vary;                    // dotted key
  std::vector<std::string> values;
  RunRequest run;
};

// Loads a bundle's scenario with KEY=VALUE overrides and checks it.
scenario::Scene load_with_overrides(const std::filesystem::path& bundle,
                                    const std::vector<std::string>& overrides);

// Returns the exit code: 0 when every run succeeded.
int sweep(const SweepRequest& request);

}  // namespace cosim::tool
