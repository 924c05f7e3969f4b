#include "overfall_report.hpp"

#include <fmt/format.h>

#include <cmath>

namespace cosim::mps {

OverfallReport::OverfallReport(double brink_x, double discharge, double average_from,
                               const FluidSystem& system, const OpenBoundaries& boundaries)
    : brink_x_(brink_x),
      discharge_(discharge),
      average_from_(average_from),
      critical_depth_(std::cbrt(discharge * discharge / system.parameters().gravity.norm())),
      particle_volume_(fill_volume_per_particle(system.parameters())),
      width_(system.parameters().dimension == 3 ? boundaries.settings().width : 1.0) {}

OverfallReport::Band OverfallReport::band(const FluidSystem& system, double x0, double x1) const {
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
  Band result;
  result.depth = count * particle_volume_ / ((x1 - x0) * width_);
  if (count > 0 && sum_u > 0.0) {
    const double mean = sum_u / count;
    result.energy_coefficient = sum_u3 / count / (mean * mean * mean);
  }
  return result;
}

void OverfallReport::observe(const FluidSystem& system, const OpenBoundaries& boundaries) {
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
  const double l0 = system.parameters().particle_spacing;
  brink_sum_ += band(system, brink_x_ - l0, brink_x_).depth;
  const double upstream = brink_x_ - 4.0 * critical_depth_;
  const Band near_critical = band(system, upstream - l0, upstream + l0);
  upstream_sum_ += near_critical.depth;
  alpha_sum_ += near_critical.energy_coefficient;
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
