// The `replay` section of a scenario: which participant to play back, from which event log.
#pragma once

#include <filesystem>
#include <string>

#include "cosim/scenario/section.hpp"

namespace cosim::replay {

struct ReplaySettings {
  std::string participant;
  std::filesystem::path event_log;
};

ReplaySettings parse_settings(scenario::Section& section);

}  // namespace cosim::replay
