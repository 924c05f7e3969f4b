#include "cosim/prescribed_flow/config.hpp"

namespace cosim::prescribed_flow {

using scenario::Range;

ProfileSettings parse_settings(scenario::Section& section) {
  ProfileSettings settings;
  const std::string profile = section.text(
      "profile", "uniform", {"uniform", "log_law", "seed004_flowing", "seed004_capture"});
  settings.kind = profile_kind_from_name(profile);
  settings.bed_point = section.vector3("bed_point", settings.bed_point);
  settings.bed_normal = section.vector3("bed_normal", settings.bed_normal);
  if (settings.bed_normal.norm() == 0.0) section.fail("bed_normal", "must not be zero");
  const bool needs_depth = settings.kind == ProfileKind::seed004_flowing ||
                           settings.kind == ProfileKind::seed004_capture;
  if (needs_depth) {
    settings.depth = section.number("depth", Range::positive());
  } else if (section.has("depth")) {
    settings.depth = section.number("depth", Range::positive());
  }
  if (settings.kind == ProfileKind::log_law) {
    settings.direction = section.vector3("direction", settings.direction);
    if (settings.direction.norm() == 0.0) section.fail("direction", "must not be zero");
    settings.shear_velocity = section.number("shear_velocity", Range::non_negative());
    settings.roughness_length = section.number("roughness_length", Range::positive());
  } else {
    settings.velocity = section.vector3("velocity");
  }
  if (settings.kind == ProfileKind::seed004_capture) {
    settings.dam_point = section.vector3("dam_point");
    settings.capture_length = section.number("capture_length", Range::positive());
  }
  settings.start_time = section.number("start_time", 0.0, Range::non_negative());
  if (section.has("end_time")) {
    settings.end_time = section.number("end_time", Range::non_negative());
    if (settings.end_time < settings.start_time) {
      section.fail("end_time", "must not be before start_time");
    }
  }
  settings.ramp_time = section.number("ramp_time", 0.0, Range::non_negative());
  return settings;
}

}  // namespace cosim::prescribed_flow
