// Every participant kind `cosim` can start, with the parser that checks its section before the
// run begins (the process parses the same section again with the same code).
#include "cosim/prescribed_flow/config.hpp"
#include "cosim/replay/config.hpp"
#include "dem_config.hpp"
#include "fluid_config.hpp"
#include "runner.hpp"
#include "vegetation_config.hpp"

namespace cosim::tool {

const std::map<std::string, scenario::ParticipantParser>& participant_parsers() {
  static const std::map<std::string, scenario::ParticipantParser> parsers{
      {"prescribed_flow", [](scenario::Section& section,
                             const scenario::Scene&) { prescribed_flow::parse_settings(section); }},
      {"replay",
       [](scenario::Section& section, const scenario::Scene&) { replay::parse_settings(section); }},
      {"debris_dem",
       [](scenario::Section& section, const scenario::Scene& scene) {
         dem::parse_config(section, scene);
       }},
      {"fluid_mps",
       [](scenario::Section& section, const scenario::Scene& scene) {
         mps::parse_config(section, scene);
       }},
      {"vegetation_beam",
       [](scenario::Section& section, const scenario::Scene& scene) {
         vegetation::parse_config(section, scene);
       }},
  };
  return parsers;
}

}  // namespace cosim::tool
