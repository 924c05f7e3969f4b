// Analytic flow fields that answer a solid's samples in place of a fluid solver: uniform flow,
// the log law, and the two debris-flow profiles of seed 004 (eq. 50 while flowing, eq. 51-53
// upstream of a check dam that has started to trap debris).
#pragma once

#include <Eigen/Core>
#include <concepts>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "cosim/scenario/parameters.hpp"

namespace cosim::prescribed_flow {

enum class ProfileKind { uniform, log_law, seed004_flowing, seed004_capture };

ProfileKind profile_kind_from_name(const std::string& name);
std::string profile_kind_name(ProfileKind kind);

struct ProfileSettings {
  ProfileKind kind = ProfileKind::uniform;
  // Uniform velocity, or the reference velocity U of seed 004 (its value at the free surface).
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  // Log law: u(z) = shear_velocity / kappa * ln(z / roughness_length) along `direction`.
  Eigen::Vector3d direction = Eigen::Vector3d::UnitX();
  double shear_velocity = 0.0;
  double roughness_length = 0.0;
  // The bed: a point on it and its upward normal; z is the height above it along the normal.
  Eigen::Vector3d bed_point = Eigen::Vector3d::Zero();
  Eigen::Vector3d bed_normal = Eigen::Vector3d::UnitZ();  // world z is up
  // Flow depth h: points above it are in air (no velocity, water fraction 0).
  double depth = std::numeric_limits<double>::infinity();
  // Seed 004 capture phase: points less than capture_length upstream of the dam plane (through
  // dam_point, facing the flow) feel the ponded profile of eq. 51-53.
  Eigen::Vector3d dam_point = Eigen::Vector3d::Zero();
  double capture_length = 0.0;
  // Water flows only in [start_time, end_time]; its speed ramps up linearly over ramp_time.
  double start_time = 0.0;
  double end_time = std::numeric_limits<double>::infinity();
  double ramp_time = 0.0;
};

inline constexpr scenario::Choices<ProfileKind, 4> kProfiles{
    {{"uniform", ProfileKind::uniform},
     {"log_law", ProfileKind::log_law},
     {"seed004_flowing", ProfileKind::seed004_flowing},
     {"seed004_capture", ProfileKind::seed004_capture}}};

// The keys of `participants.prescribed_flow`, declared once for the parser, the library's check
// (validate_settings) and `cosim keys` (cosim/scenario/parameters.hpp).
template <class P, class V>
requires std::same_as<std::remove_const_t<P>, ProfileSettings>
void visit_parameters(P& s, V& v) {
  using scenario::Key;
  using scenario::Range;
  v(Key("profile").doc("the analytic flow"), s.kind, kProfiles);
  const bool log_law = s.kind == ProfileKind::log_law;
  const bool capture = s.kind == ProfileKind::seed004_capture;
  const bool seed = capture || s.kind == ProfileKind::seed004_flowing;
  v(Key("bed_point").unit("m").doc("a point on the bed"), s.bed_point);
  v(Key("bed_normal").doc("the bed's upward normal"), s.bed_normal);
  v.rule("bed_normal", s.bed_normal.norm() > 0.0, "must not be zero");
  const Key depth = Key("depth")
                        .unit("m")
                        .in(Range::positive())
                        .doc("flow depth h above the bed; required by the seed004 profiles");
  v(seed ? depth.needed() : depth.omitted_means("inf: no free surface"), s.depth);
  const char* law = "profile: log_law";
  v(Key("direction").only_with(log_law, law).doc("flow direction of the log law"), s.direction);
  v.rule("direction", !log_law || s.direction.norm() > 0.0, "must not be zero");
  v(Key("shear_velocity")
        .unit("m/s")
        .in(Range::non_negative())
        .needed()
        .only_with(log_law, law)
        .doc("u*"),
    s.shear_velocity);
  v(Key("roughness_length")
        .unit("m")
        .in(Range::positive())
        .needed()
        .only_with(log_law, law)
        .doc("z0"),
    s.roughness_length);
  v(Key("velocity")
        .unit("m/s")
        .needed()
        .only_with(!log_law, "profile: uniform, seed004_flowing, seed004_capture")
        .doc("uniform velocity, or seed 004's surface velocity U"),
    s.velocity);
  const char* ponded = "profile: seed004_capture";
  v(Key("dam_point").unit("m").needed().only_with(capture, ponded).doc("a point on the dam plane"),
    s.dam_point);
  v(Key("capture_length")
        .unit("m")
        .in(Range::positive())
        .needed()
        .only_with(capture, ponded)
        .doc("reach of the ponded profile upstream of the dam"),
    s.capture_length);
  v(Key("start_time").unit("s").in(Range::non_negative()).doc("water flows from"), s.start_time);
  v(Key("end_time")
        .unit("s")
        .in(Range::non_negative())
        .omitted_means("inf: never stops")
        .doc("water flows until"),
    s.end_time);
  v.rule("end_time", s.end_time >= s.start_time, "must not be before start_time");
  v(Key("ramp_time").unit("s").in(Range::non_negative()).doc("linear ramp of the speed"),
    s.ramp_time);
}

// The library's check: the declared ranges and rules; throws scenario::ParameterError.
inline void validate_settings(const ProfileSettings& settings) {
  scenario::check_parameters(settings, "prescribed_flow");
}

inline constexpr double kVonKarman = 0.41;

class PrescribedFlow {
 public:
  explicit PrescribedFlow(ProfileSettings settings);

  // Velocity and water fraction (1 submerged, 0 dry) at each point at `time`.
  void sample(double time, std::span<const Eigen::Vector3d> points,
              std::vector<Eigen::Vector3d>& velocity, std::vector<double>& water_fraction) const;

  // Height above the bed.
  double height(const Eigen::Vector3d& point) const;
  // Seed 004: the ponded depth h_D just upstream of the dam, from the highest point there
  // (never less than the approach depth h).
  double ponded_depth(std::span<const Eigen::Vector3d> points) const;
  const ProfileSettings& settings() const { return settings_; }

 private:
  bool in_capture_region(const Eigen::Vector3d& point) const;
  double time_factor(double time) const;

  ProfileSettings settings_;
  Eigen::Vector3d flow_direction_;
};

}  // namespace cosim::prescribed_flow
