// Eulerian observation of a FluidSystem: velocity time series at fixed points, discharge through
// a vertical line, gauge lines counting the fluid crossing them, water level.
#pragma once

#include <Eigen/Core>
#include <limits>
#include <string>
#include <vector>

#include "cosim/fluid_mps/fluid_system.hpp"

namespace cosim::mps {

// Fixed observation points: each record() samples the ensemble-averaged fluid velocity and the
// water fraction (presence) within `radius` of every point (FluidSystem::sample_velocity).
class ObservationPoints {
 public:
  ObservationPoints(std::vector<Eigen::Vector3d> points, double radius);

  void record(const FluidSystem& system);

  const std::vector<Eigen::Vector3d>& points() const { return points_; }
  const std::vector<double>& times() const { return times_; }
  // velocity(s)[q]: sample s, point q.
  const std::vector<std::vector<Eigen::Vector3d>>& velocity() const { return velocity_; }
  const std::vector<std::vector<double>>& water_fraction() const { return water_fraction_; }
  // Time-averaged velocity of point q over the samples with time in [t0, t1] (wet or not).
  Eigen::Vector3d mean_velocity(std::size_t q, double t0 = -1e300, double t1 = 1e300) const;
  // CSV: time, then u, v, w, water fraction for each point.
  void write_csv(const std::string& path) const;

 private:
  std::vector<Eigen::Vector3d> points_;
  double radius_;
  std::vector<double> times_;
  std::vector<std::vector<Eigen::Vector3d>> velocity_;
  std::vector<std::vector<double>> water_fraction_;
};

// Discharge per unit width [m^2/s] (2D) or discharge [m^3/s] (3D, per the band's z extent
// ignored) through the vertical line x = `x`, y in [y_min, y_max]: the fluid particles with
// |x_i - x| < band / 2 carry q = sum u_x,i l0^D / band (band: default l0).
double discharge_through_line(const FluidSystem& system, double x,
                              double y_min = -std::numeric_limits<double>::infinity(),
                              double y_max = std::numeric_limits<double>::infinity(),
                              double band = -1.0);

// Pressure a wall-mounted sensor reads [Pa]: the mean pressure of the fluid and wall particles
// (the wall particles' pressure is solved in the Poisson equation; dummies carry none) within
// `radius` of `point`, so a sensor on a wall face averages the water against it and the wall's
// surface layer, wherever the lattice put the face within l0 / 2 of the drawn one. 0 if none.
double wall_pressure_at(const FluidSystem& system, const Eigen::Vector3d& point, double radius);
// Water depth at a gauge [m]: the fluid volume above the horizontal position (x, y), each
// particle's l0^3 spread over the bed by the normalised bilinear tent
// T(dx) T(dy), T(d) = max(0, 1 - |d| / h) / h (3D; in 2D T(dx) alone, volume l0^2). The tent is
// a box of width h convolved with itself, so on a perfect lattice with h a whole number of cells
// the weights of a column sum to 1 / l0^2 wherever the gauge stands (still water reads its depth
// exactly), and unlike a sharp footprint the reading does not jump when a particle crosses its
// edge; a splash above the gauge adds its volume, not its height.
double water_depth_at(const FluidSystem& system, double x, double y, double half_width);
// Water level: highest fluid particle with x in [x0, x1] plus l0/2, or -inf if none.
double water_level(const FluidSystem& system, double x0, double x1);

// Counts fluid particles crossing the vertical line x = `x` (y in [y_min, y_max]) between
// successive update() calls: +1 downstream (+x), -1 upstream. Minimum-image displacements across
// a periodic seam; particles that changed kind (recycled / dissolved) are not counted.
class GaugeLine {
 public:
  explicit GaugeLine(double x, double y_min = -std::numeric_limits<double>::infinity(),
                     double y_max = std::numeric_limits<double>::infinity());
  void update(const FluidSystem& system);
  long net_particles() const { return net_; }
  // Volume through the line [m^3, m^2 in 2D] = net particles l0^D; mass = rho volume.
  double volume(const FluidSystem& system) const;
  void reset() { net_ = 0; }

 private:
  double x_, y_min_, y_max_;
  std::vector<Eigen::Vector3d> previous_;
  std::vector<ParticleKind> previous_kind_;
  long net_ = 0;
};

}  // namespace cosim::mps
