#include "cosim/prescribed_flow/profiles.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cosim::prescribed_flow {

ProfileKind profile_kind_from_name(const std::string& name) {
  if (name == "uniform") return ProfileKind::uniform;
  if (name == "log_law") return ProfileKind::log_law;
  if (name == "seed004_flowing") return ProfileKind::seed004_flowing;
  if (name == "seed004_capture") return ProfileKind::seed004_capture;
  throw std::invalid_argument("unknown flow profile '" + name + "'");
}

std::string profile_kind_name(ProfileKind kind) {
  switch (kind) {
    case ProfileKind::uniform:
      return "uniform";
    case ProfileKind::log_law:
      return "log_law";
    case ProfileKind::seed004_flowing:
      return "seed004_flowing";
    case ProfileKind::seed004_capture:
      return "seed004_capture";
  }
  return "?";
}

PrescribedFlow::PrescribedFlow(ProfileSettings settings) : settings_(std::move(settings)) {
  validate_settings(settings_);  // the declared ranges and rules (profiles.hpp)
  settings_.bed_normal.normalize();
  const Eigen::Vector3d along =
      settings_.kind == ProfileKind::log_law ? settings_.direction : settings_.velocity;
  flow_direction_ = along.norm() > 0.0 ? along.normalized() : Eigen::Vector3d::UnitX();
}

double PrescribedFlow::height(const Eigen::Vector3d& point) const {
  return (point - settings_.bed_point).dot(settings_.bed_normal);
}

bool PrescribedFlow::in_capture_region(const Eigen::Vector3d& point) const {
  const double upstream_distance = (settings_.dam_point - point).dot(flow_direction_);
  return upstream_distance >= 0.0 && upstream_distance <= settings_.capture_length;
}

double PrescribedFlow::ponded_depth(std::span<const Eigen::Vector3d> points) const {
  double highest = settings_.depth;
  for (const auto& point : points) {
    if (in_capture_region(point)) highest = std::max(highest, height(point));
  }
  return highest;
}

double PrescribedFlow::time_factor(double time) const {
  if (time < settings_.start_time || time > settings_.end_time) return 0.0;
  if (settings_.ramp_time <= 0.0) return 1.0;
  return std::min(1.0, (time - settings_.start_time) / settings_.ramp_time);
}

void PrescribedFlow::sample(double time, std::span<const Eigen::Vector3d> points,
                            std::vector<Eigen::Vector3d>& velocity,
                            std::vector<double>& water_fraction) const {
  velocity.assign(points.size(), Eigen::Vector3d::Zero());
  water_fraction.assign(points.size(), 0.0);
  const double factor = time_factor(time);
  if (time < settings_.start_time || time > settings_.end_time) return;  // no water yet / any more
  const double depth = settings_.depth;
  const double ponded = settings_.kind == ProfileKind::seed004_capture ? ponded_depth(points) : 0.0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double z = height(points[i]);
    const bool capture =
        settings_.kind == ProfileKind::seed004_capture && in_capture_region(points[i]);
    const double surface = capture ? ponded : depth;
    if (z > surface) continue;  // in air: seed 004 gives no fluid force above the surface
    water_fraction[i] = 1.0;
    const double z_clamped = std::max(z, 0.0);
    switch (settings_.kind) {
      case ProfileKind::uniform:
        velocity[i] = settings_.velocity;
        break;
      case ProfileKind::log_law: {
        const double speed = z_clamped > settings_.roughness_length
                                 ? settings_.shear_velocity / kVonKarman *
                                       std::log(z_clamped / settings_.roughness_length)
                                 : 0.0;
        velocity[i] = speed * flow_direction_;
        break;
      }
      case ProfileKind::seed004_flowing:
      case ProfileKind::seed004_capture:
        if (!capture) {
          // Eq. 50: 0.8 U on the bed rising linearly to U at the surface.
          velocity[i] = (z_clamped / depth / 5.0 + 4.0 / 5.0) * settings_.velocity;
        } else {
          // Eq. 51-52: a trapezoidal profile over the ponded depth that carries the approach
          // discharge (mean 0.9 U h = 0.5 (alpha + beta) U h_D).
          double alpha = 1.8 * depth / ponded - 1.0;
          double beta = 1.0;
          if (alpha <= 0.1) {
            alpha = 0.1;
            beta = 1.8 * depth / ponded - alpha;
          }
          // Eq. 53.
          velocity[i] = ((beta - alpha) * z_clamped / ponded + alpha) * settings_.velocity;
        }
        break;
    }
    velocity[i] *= factor;
  }
}

}  // namespace cosim::prescribed_flow
