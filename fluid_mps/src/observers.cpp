#include "cosim/fluid_mps/observers.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <stdexcept>

namespace cosim::mps {

ObservationPoints::ObservationPoints(std::vector<Eigen::Vector3d> points, double radius)
    : points_(std::move(points)), radius_(radius) {
  if (!(radius > 0.0)) throw std::invalid_argument("ObservationPoints: radius must be > 0");
}

void ObservationPoints::record(const FluidSystem& system) {
  std::vector<double> fraction;
  velocity_.push_back(system.sample_velocity(points_, radius_, &fraction));
  water_fraction_.push_back(std::move(fraction));
  times_.push_back(system.time());
}

Eigen::Vector3d ObservationPoints::mean_velocity(std::size_t q, double t0, double t1) const {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int count = 0;
  for (std::size_t s = 0; s < times_.size(); ++s) {
    if (times_[s] < t0 || times_[s] > t1) continue;
    sum += velocity_[s].at(q);
    ++count;
  }
  return count > 0 ? Eigen::Vector3d(sum / count) : Eigen::Vector3d::Zero();
}

void ObservationPoints::write_csv(const std::string& path) const {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("ObservationPoints: cannot write " + path);
  out << "time";
  for (std::size_t q = 0; q < points_.size(); ++q) {
    out << ",u" << q << ",v" << q << ",w" << q << ",water" << q;
  }
  out << "\n";
  out.precision(10);
  for (std::size_t s = 0; s < times_.size(); ++s) {
    out << times_[s];
    for (std::size_t q = 0; q < points_.size(); ++q) {
      const Eigen::Vector3d& u = velocity_[s][q];
      out << "," << u.x() << "," << u.y() << "," << u.z() << "," << water_fraction_[s][q];
    }
    out << "\n";
  }
}

double discharge_through_line(const FluidSystem& system, double x, double y_min, double y_max,
                              double band) {
  const MpsParameters& p = system.parameters();
  const double l0 = p.particle_spacing;
  if (band <= 0.0) band = l0;
  double sum = 0.0;
  for (int i = 0; i < system.particle_count(); ++i) {
    if (system.kinds()[i] != ParticleKind::fluid) continue;
    const Eigen::Vector3d& r = system.positions()[i];
    const double dx = p.periodic.wrap(Eigen::Vector3d(r.x() - x, 0.0, 0.0)).x();
    if (std::abs(dx) >= 0.5 * band || r.y() < y_min || r.y() > y_max) continue;
    sum += system.velocities()[i].x();
  }
  return sum * fill_volume_per_particle(p) / band;
}

double water_level(const FluidSystem& system, double x0, double x1) {
  double top = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < system.particle_count(); ++i) {
    if (system.kinds()[i] != ParticleKind::fluid) continue;
    const Eigen::Vector3d& r = system.positions()[i];
    if (r.x() >= x0 && r.x() <= x1) top = std::max(top, r.y());
  }
  return top + 0.5 * system.parameters().particle_spacing;
}

double wall_pressure_at(const FluidSystem& system, const Eigen::Vector3d& point, double radius) {
  double sum = 0.0;
  int count = 0;
  for (int i = 0; i < system.particle_count(); ++i) {
    const ParticleKind kind = system.kinds()[i];
    if (kind != ParticleKind::fluid && kind != ParticleKind::wall) continue;
    if ((system.positions()[i] - point).squaredNorm() >= radius * radius) continue;
    sum += system.pressures()[i];
    ++count;
  }
  return count > 0 ? sum / count : 0.0;
}

double water_depth_at(const FluidSystem& system, double x, double y, double half_width) {
  const MpsParameters& p = system.parameters();
  const double h = half_width;
  auto tent = [h](double d) { return std::max(0.0, 1.0 - std::abs(d) / h) / h; };
  double weight = 0.0;
  for (int i = 0; i < system.particle_count(); ++i) {
    if (system.kinds()[i] != ParticleKind::fluid) continue;
    const Eigen::Vector3d& r = system.positions()[i];
    const double wx = tent(r.x() - x);
    if (wx == 0.0) continue;
    weight += p.dimension == 3 ? wx * tent(r.y() - y) : wx;
  }
  return weight * fill_volume_per_particle(p);
}

GaugeLine::GaugeLine(double x, double y_min, double y_max) : x_(x), y_min_(y_min), y_max_(y_max) {}

void GaugeLine::update(const FluidSystem& system) {
  const int n = system.particle_count();
  const PeriodicBoundary& periodic = system.parameters().periodic;
  if (static_cast<int>(previous_.size()) == n) {
    for (int i = 0; i < n; ++i) {
      if (system.kinds()[i] != ParticleKind::fluid || previous_kind_[i] != ParticleKind::fluid) {
        continue;
      }
      const Eigen::Vector3d& before = previous_[i];
      const Eigen::Vector3d after = before + periodic.wrap(system.positions()[i] - before);
      // Gauge position seen from the particle's side of the seam.
      const double gauge =
          before.x() + periodic.wrap(Eigen::Vector3d(x_ - before.x(), 0.0, 0.0)).x();
      const double y = 0.5 * (before.y() + after.y());
      if (y < y_min_ || y > y_max_) continue;
      if (before.x() < gauge && after.x() >= gauge) ++net_;
      if (before.x() >= gauge && after.x() < gauge) --net_;
    }
  }
  previous_ = system.positions();
  previous_kind_ = system.kinds();
}

double GaugeLine::volume(const FluidSystem& system) const {
  const MpsParameters& p = system.parameters();
  return static_cast<double>(net_) * fill_volume_per_particle(p);
}

}  // namespace cosim::mps
