#include "cosim/replay/config.hpp"

namespace cosim::replay {

ReplaySettings parse_settings(scenario::Section& section) {
  ReplaySettings settings;
  settings.participant = section.text("participant");
  settings.event_log = section.existing_file("log");
  return settings;
}

}  // namespace cosim::replay
