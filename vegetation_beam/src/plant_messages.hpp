// The plant field's error text, shared by its source files (internal).
#pragma once

#include <string>

namespace cosim::vegetation {

// "vegetation_beam: plant P node N: WHAT", the prefix of every stability error.
inline std::string plant_message(int plant, int node, const std::string& what) {
  return "vegetation_beam: plant " + std::to_string(plant) + " node " + std::to_string(node) +
         ": " + what;
}

}  // namespace cosim::vegetation
