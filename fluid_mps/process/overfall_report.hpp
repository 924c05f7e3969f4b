// Check of a free overfall (open_channel with the discharge control on a horizontal bed that ends
// at x = length): the end depth at the brink against Rouse's h_e = 0.715 h_c, h_c = (q^2 / g)^(1/3)
// the critical depth of the prescribed discharge per width q (Rouse 1936, "Discharge
// characteristics of the free overfall", Civil Engineering 6(4); 0.705-0.72 in later experiments,
// e.g. Dey 2002, ISH J. Hydraul. Eng.), and the mass balance (water released at the inflow and
// removed at the outflow) against q. The depth 4 h_c upstream of the brink, near where Rouse
// found the critical section (3-4 h_c), and the energy coefficient alpha of the velocity profile
// there are reported as information: a profile far from uniform raises the critical depth of
// the mean velocity to (alpha q^2 / g)^(1/3) (Chow 1959, Open-Channel Hydraulics, 2-7), and the
// brink depth with it.
#pragma once

#include "cosim/coupler/metrics.hpp"
#include "cosim/fluid_mps/boundaries.hpp"
#include "cosim/fluid_mps/fluid_system.hpp"

namespace cosim::mps {

// Rouse's end-depth ratio h_e / h_c of a free overfall from a horizontal channel.
inline constexpr double kRouseEndDepthRatio = 0.715;

class OverfallReport {
 public:
  // brink_x: the end of the bed (the library's x) [m]; discharge: q per width [m^2/s]. The
  // system and its open boundaries give gravity, the particles' volume and the channel's width.
  OverfallReport(double brink_x, double discharge, double average_from, const FluidSystem& system,
                 const OpenBoundaries& boundaries);
  // After every window.
  void observe(const FluidSystem& system, const OpenBoundaries& boundaries);
  void report(coupler::MetricsReport& report) const;

  // The water over x in [x0, x1): its mean depth (its volume there over the bed area: the band's
  // length, times the width in 3D) [m] and the energy (Coriolis) coefficient of its streamwise
  // velocity, alpha = mean(u^3) / mean(u)^3 over its particles (equal volumes): 1 for a uniform
  // profile, 1.54 for the laminar half-parabola of a film (Chow 1959, 2-7); 0 when no water
  // moves there.
  struct Band {
    double depth = 0, energy_coefficient = 0;
  };
  Band band(const FluidSystem& system, double x0, double x1) const;

 private:
  double brink_x_, discharge_, average_from_;
  double critical_depth_;   // (q^2 / g)^(1/3) [m]
  double particle_volume_;  // [m^3, m^2 in 2D]
  double width_;            // of the channel in 3D, 1 in 2D [m]
  bool averaging_ = false;
  int samples_ = 0;
  double brink_sum_ = 0, upstream_sum_ = 0, alpha_sum_ = 0;
  double start_time_ = 0, end_time_ = 0;
  long released_start_ = 0, released_end_ = 0, recycled_start_ = 0, recycled_end_ = 0;
};

}  // namespace cosim::mps
