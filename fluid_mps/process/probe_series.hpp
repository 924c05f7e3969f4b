// Point sensors against a measured record: wall pressure probes and water-depth gauges sampled
// every window and compared with the columns of a CSV of measurements over its time span, e.g.
// SPHERIC benchmark 2 (Kleefsman et al. 2005; references/spheric_test2.md).
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <vector>

#include "cosim/coupler/metrics.hpp"
#include "cosim/fluid_mps/fluid_system.hpp"

namespace cosim::mps {

struct ReferenceSeries;

// A CSV of measurements: '#' comment lines, one header line (time first), then one row a
// sample, times increasing.
struct MeasuredTable {
  std::filesystem::path file;
  std::vector<std::string> columns;           // after the time column
  std::vector<double> times;                  // [s]
  std::vector<std::vector<double>> values;    // [column][sample], SI units
  int column(const std::string& name) const;  // -1 if absent
};
// Throws std::runtime_error naming file:line on a malformed row.
MeasuredTable read_measured_table(const std::filesystem::path& file);

struct ProbeSeriesSettings {
  struct Sensor {
    std::string column;  // of the measured table
    Eigen::Vector3d at;  // solver frame [m]; a gauge uses the horizontal coordinates only
  };
  std::vector<Sensor> pressure_probes, depth_gauges;
  double probe_radius = 0;      // wall_pressure_at [m]
  double gauge_half_width = 0;  // water_depth_at: half-width h of the bilinear tent [m]
  // Arrival: the first time a probe reads this fraction of its measured peak in the window.
  double arrival_fraction = 0.1;
  MeasuredTable measured;
};

class ProbeSeriesReport {
 public:
  explicit ProbeSeriesReport(ProbeSeriesSettings settings);
  void observe(const FluidSystem& system);
  void report(coupler::MetricsReport& report) const;
  std::vector<ReferenceSeries> series() const;

 private:
  ProbeSeriesSettings settings_;
  std::vector<double> times_;
  std::vector<std::vector<double>> pressures_, depths_;  // [sensor][sample]
};

}  // namespace cosim::mps
