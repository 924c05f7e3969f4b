// Reference comparisons of the fluid scenes: the dam-break surge front and residual column of
// Martin & Moyce (1952), hydrostatic pressure in still water, and point sensors against a
// measured record (probe_series.hpp).
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "cosim/coupler/metrics.hpp"
#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/observers.hpp"
#include "fluid_config.hpp"

namespace cosim::mps {

// Running sums of the momentum the fluid received, by source [N s/m in 2D].
struct FluidImpulses {
  Eigen::Vector3d solids = Eigen::Vector3d::Zero();          // minus the solids' drag
  Eigen::Vector3d wall_viscous = Eigen::Vector3d::Zero();    // bed shear (viscous part)
  Eigen::Vector3d wall_collision = Eigen::Vector3d::Zero();  // collision model against walls
  Eigen::Vector3d wall_pressure = Eigen::Vector3d::Zero();   // pressure gradient of walls
  Eigen::Vector3d fluid_pressure = Eigen::Vector3d::Zero();  // fluid-fluid: non-conservation
  Eigen::Vector3d shifting = Eigen::Vector3d::Zero();        // shifted_velocity: taylor's gain
};

// A time series with its measured reference curve, in SI units, for the output file.
struct ReferenceSeries {
  std::string name, unit, description, source;
  std::vector<double> times, values, reference_times, reference_values;
};

// Samples the run at the end of every window and reports against the reference at the end.
class ReferenceTracker {
 public:
  // gravity: its magnitude along the vertical [m/s^2]. dimension 3: the vertical is z and the
  // hydrostatic probes lie at y = probe_across (mid-width of the tank); 2D: the plane's y.
  ReferenceTracker(const ReferenceSettings& settings, double gravity, int dimension = 2,
                   double probe_across = 0.0);
  void observe(const FluidSystem& system, const FluidImpulses& impulses,
               const ObservationPoints* observation);
  void report(coupler::MetricsReport& report) const;
  // The observed series behind the metrics (dam break: surge front, residual height).
  std::vector<ReferenceSeries> series() const;

 private:
  void report_shear_layer(const std::vector<std::pair<double, double>>& profile,
                          double interior_velocity, coupler::MetricsReport& report) const;
  struct Curve {
    std::vector<double> x, y;
  };
  ReferenceSettings settings_;
  double gravity_;
  int dimension_ = 2;
  double probe_across_ = 0;
  Curve front_reference_, height_reference_;
  std::vector<double> times_, fronts_, heights_;
  std::vector<double> pressure_sums_;
  int pressure_samples_ = 0;
  double kinetic_energy_sum_ = 0.0;  // sum over samples of the fluid's mean u^2 / 2 [J/kg]
  double level_sum_ = 0.0;           // hydrostatic: sum over samples of the water level [m]
  double density_ = 1000;
  double last_time_ = 0;
  // canopy_balance
  const ObservationPoints* observation_ = nullptr;
  bool averaging_ = false;
  double average_start_ = 0;
  FluidImpulses impulses_start_, impulses_end_;
  Eigen::Vector3d momentum_start_ = Eigen::Vector3d::Zero(),
                  momentum_end_ = Eigen::Vector3d::Zero();
  double driving_per_area_sum_ = 0;  // summed per observation, averaged at the end
  int driving_samples_ = 0;
  double period_length_ = 1, viscosity_ = 1e-6;
  std::shared_ptr<ProbeSeriesReport> probes_;  // probe_series (probe_series.hpp)
};

}  // namespace cosim::mps
