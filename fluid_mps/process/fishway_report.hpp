// Checks of the fishway scenes (seed 001): the mass balance (discharge over every weir and the
// outflow against the inflow, once the pools have filled) and the sharp-crested weir equation
// at the weirs that spill freely.
#pragma once

#include <optional>

#include "cosim/coupler/metrics.hpp"
#include "cosim/fluid_mps/boundaries.hpp"
#include "cosim/fluid_mps/fishway.hpp"

namespace cosim::mps {

class FishwayReport {
 public:
  // inflow_discharge: the prescribed q [m^2/s] of the pool fishway; for the periodic pool the
  // discharge its fill level was chosen for (reported, not checked).
  FishwayReport(std::vector<Weir> weirs, double particle_spacing, double average_from,
                double inflow_discharge, bool periodic);
  // After every window. `boundaries` is null for the periodic pool.
  void observe(const FluidSystem& system, const OpenBoundaries* boundaries);
  void report(coupler::MetricsReport& report) const;

 private:
  WeirGauges gauges_;
  double average_from_, inflow_discharge_, gravity_ = 9.81;
  bool periodic_;
  bool averaging_ = false;
  double start_time_ = 0, end_time_ = 0;
  long released_start_ = 0, released_end_ = 0, recycled_start_ = 0, recycled_end_ = 0;
  double particle_area_;
};

}  // namespace cosim::mps
