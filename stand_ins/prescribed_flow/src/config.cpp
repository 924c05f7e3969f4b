#include "cosim/prescribed_flow/config.hpp"

#include "cosim/scenario/parameter_reader.hpp"

namespace cosim::prescribed_flow {

ProfileSettings parse_settings(scenario::Section& section) {
  ProfileSettings settings;
  scenario::read_parameters(section, settings);  // the keys declared in profiles.hpp
  scenario::check_at_keys(section, [&] { validate_settings(settings); });
  return settings;
}

}  // namespace cosim::prescribed_flow
