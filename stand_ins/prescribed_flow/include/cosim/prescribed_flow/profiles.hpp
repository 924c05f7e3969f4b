// Analytic flow fields that answer a solid's samples in place of a fluid solver: uniform flow,
// the log law, and the two debris-flow profiles of seed 004 (eq. 50 while flowing, eq. 51-53
// upstream of a check dam that has started to trap debris).
#pragma once

#include <Eigen/Core>
#include <limits>
#include <span>
#include <string>
#include <vector>

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
