// The `prescribed_flow` section of a scenario.
#pragma once

#include "cosim/prescribed_flow/profiles.hpp"
#include "cosim/scenario/section.hpp"

namespace cosim::prescribed_flow {

// Reads and checks the section; errors name the file, line and key.
ProfileSettings parse_settings(scenario::Section& section);

}  // namespace cosim::prescribed_flow
