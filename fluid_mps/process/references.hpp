// Reference comparisons of the fluid scenes: the dam-break surge front and residual column of
// Martin & Moyce (1952), and hydrostatic pressure in still water.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "cosim/coupler/metrics.hpp"
#include "cosim/fluid_mps/fluid_system.hpp"
#include "fluid_config.hpp"

namespace cosim::mps {

// Samples the run at the end of every window and reports against the reference at the end.
class ReferenceTracker {
 public:
  ReferenceTracker(const ReferenceSettings& settings, double gravity);
  void observe(const FluidSystem& system);
  void report(coupler::MetricsReport& report) const;

 private:
  struct Curve {
    std::vector<double> x, y;
  };
  ReferenceSettings settings_;
  double gravity_;
  Curve front_reference_, height_reference_;
  std::vector<double> times_, fronts_, heights_;
  std::vector<double> pressure_sums_;
  int pressure_samples_ = 0;
  double density_ = 1000;
  double last_time_ = 0;
};

}  // namespace cosim::mps
