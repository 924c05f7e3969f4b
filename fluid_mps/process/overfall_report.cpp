#include "overfall_report.hpp"

#include <fmt/format.h>

#include <cmath>

namespace cosim::mps {

OverfallReport::OverfallReport(double brink_x, double discharge, double average_from)
    : brink_x_(brink_x), discharge_(discharge), average_from_(average_from) {}

double OverfallReport::band_depth(const FluidSystem& system, double x0, double x1, double width) {
  const MpsParameters& p = system.parameters();
  int inside = 0;
  for (int i = 0; i < system.particle_count(); ++i) {
    if (system.kinds()[i] != ParticleKind::fluid) continue;
    const double x = system.positions()[i].x();
    inside += x >= x0 && x < x1;
  }
  return inside * fill_volume_per_particle(p) / ((x1 - x0) * (p.dimension == 3 ? width : 1.0));
}

double OverfallReport::energy_coefficient(const FluidSystem& system, double x0, double x1) {
  double sum_u = 0.0, sum_u3 = 0.0;
  int count = 0;
  for (int i = 0; i < system.particle_count(); ++i) {
    if (system.kinds()[i] != ParticleKind::fluid) continue;
    const double x = system.positions()[i].x();
    if (x < x0 || x >= x1) continue;
    const double u = system.velocities()[i].x();
    sum_u += u;
    sum_u3 += u * u * u;
    ++count;
  }
  if (count == 0 || !(sum_u > 0.0)) return 0.0;
  const double mean = sum_u / count;
  return sum_u3 / count / (mean * mean * mean);
}

void OverfallReport::observe(const FluidSystem& system, const OpenBoundaries& boundaries) {
  const MpsParameters& p = system.parameters();
  const double l0 = p.particle_spacing;
  critical_depth_ = std::cbrt(discharge_ * discharge_ / p.gravity.norm());
  particle_volume_ = fill_volume_per_particle(p);
  width_ = p.dimension == 3 ? boundaries.settings().width : 1.0;
  if (system.time() < average_from_) return;
  if (!averaging_) {
    averaging_ = true;
    start_time_ = system.time();
    released_start_ = boundaries.dissolved_total();
    recycled_start_ = boundaries.recycled_total();
  }
  end_time_ = system.time();
  released_end_ = boundaries.dissolved_total();
  recycled_end_ = boundaries.recycled_total();
  // The brink: the last cell of the bed. Upstream: two cells around 4 h_c before it.
  brink_sum_ += band_depth(system, brink_x_ - l0, brink_x_, width_);
  const double upstream = brink_x_ - 4.0 * critical_depth_;
  upstream_sum_ += band_depth(system, upstream - l0, upstream + l0, width_);
  alpha_sum_ += energy_coefficient(system, upstream - l0, upstream + l0);
  ++samples_;
}

void OverfallReport::report(coupler::MetricsReport& report) const {
  auto& info = report.info();
  info["overfall_average_from"] = average_from_;
  info["critical_depth"] = critical_depth_;
  if (!averaging_ || samples_ == 0 || end_time_ <= start_time_) return;
  const double span = end_time_ - start_time_;
  info["overfall_averaged_seconds"] = span;
  const double brink = brink_sum_ / samples_, upstream = upstream_sum_ / samples_;
  info["brink_depth"] = brink;
  info["upstream_depth_4hc"] = upstream;
  info["upstream_depth_ratio_4hc"] = upstream / critical_depth_;
  const double alpha = alpha_sum_ / samples_;
  info["energy_coefficient_4hc"] = alpha;
  if (alpha > 0.0) {
    // Rouse's ratio on the critical depth of the measured profile instead of a uniform one.
    info["brink_depth_ratio_profile_critical"] = brink / (std::cbrt(alpha) * critical_depth_);
  }
  report.compare("brink_depth_ratio", brink / critical_depth_, kRouseEndDepthRatio, "1",
                 fmt::format("Rouse (1936) free overfall from a horizontal bed: h_e = 0.715 h_c, "
                             "h_c = {:.4g} m for q = {:.5g} m^2/s (mean over {:.3g}-{:.3g} s)",
                             critical_depth_, discharge_, start_time_, end_time_));
  // Water released at the inflow and removed at the free outflow over the averaging time, per
  // width.
  const std::string balance_source =
      fmt::format("prescribed inflow {:.5g} m^2/s (mass balance, mean over {:.3g}-{:.3g} s)",
                  discharge_, start_time_, end_time_);
  const double per_width = particle_volume_ / width_ / span;
  report.compare("released_discharge", (released_end_ - released_start_) * per_width, discharge_,
                 "m^2/s", balance_source);
  report.compare("outflow_discharge", (recycled_end_ - recycled_start_) * per_width, discharge_,
                 "m^2/s", balance_source);
}

}  // namespace cosim::mps
