#include "fishway_report.hpp"

#include <fmt/format.h>

#include <cmath>

namespace cosim::mps {

FishwayReport::FishwayReport(std::vector<Weir> weirs, double particle_spacing, double average_from,
                             double inflow_discharge, bool periodic)
    // Crest section two particles wide; head gauge four particles wide.
    : gauges_(std::move(weirs), 2.0 * particle_spacing, 4.0 * particle_spacing),
      average_from_(average_from),
      inflow_discharge_(inflow_discharge),
      periodic_(periodic),
      particle_area_(particle_spacing * particle_spacing) {}

void FishwayReport::observe(const FluidSystem& system, const OpenBoundaries* boundaries) {
  gravity_ = system.parameters().gravity.norm();
  if (system.time() < average_from_) return;
  gauges_.record(system);
  if (!averaging_) {
    averaging_ = true;
    start_time_ = system.time();
    if (boundaries) {
      released_start_ = boundaries->dissolved_total();
      recycled_start_ = boundaries->recycled_total();
    }
  }
  end_time_ = system.time();
  if (boundaries) {
    released_end_ = boundaries->dissolved_total();
    recycled_end_ = boundaries->recycled_total();
  }
}

void FishwayReport::report(coupler::MetricsReport& report) const {
  report.info()["fishway_average_from"] = average_from_;
  if (!averaging_ || end_time_ <= start_time_) return;
  const double span = end_time_ - start_time_;
  report.info()["fishway_averaged_seconds"] = span;
  report.info()["fishway_gauge_samples"] = gauges_.samples();
  const std::string balance_source =
      fmt::format("prescribed inflow {:.5g} m^2/s (mass balance, mean over {:.3g}-{:.3g} s)",
                  inflow_discharge_, start_time_, end_time_);
  if (!periodic_) {
    // Water released at the inflow and removed at the free outflow over the averaging time.
    const double released = (released_end_ - released_start_) * particle_area_ / span;
    const double outflow = (recycled_end_ - recycled_start_) * particle_area_ / span;
    report.compare("released_discharge", released, inflow_discharge_, "m^2/s", balance_source);
    report.compare("outflow_discharge", outflow, inflow_discharge_, "m^2/s", balance_source);
  } else {
    report.info()["fill_discharge"] = inflow_discharge_;
  }
  for (std::size_t w = 0; w < gauges_.size(); ++w) {
    const Weir& weir = gauges_.weirs()[w];
    const double q = gauges_.mean_discharge(w), head = gauges_.mean_head(w);
    const std::string name = fmt::format("weir_{}", w + 1);
    const bool orifice = weir.orifice_top > weir.floor;
    const double orifice_q = gauges_.mean_orifice_discharge(w);
    if (!periodic_) {
      // Everything crossing the partition: over the crest plus through the orifice.
      report.compare(orifice ? name + "_total_discharge" : name + "_discharge", q + orifice_q,
                     inflow_discharge_, "m^2/s", balance_source);
    }
    if (orifice || periodic_) report.value(name + "_discharge", q, "m^2/s");
    if (orifice) {
      report.value(name + "_orifice_discharge", orifice_q, "m^2/s");
      // Submerged orifice q = C_d a sqrt(2 g dH), dH the level difference of the two pools
      // (heads over crests one step apart); the implied C_d is reported, 0.6-0.8 is usual.
      if (w + 1 < gauges_.size()) {
        const Weir& next = gauges_.weirs()[w + 1];
        const double level_drop =
            (head + weir.crest.y()) - (gauges_.mean_head(w + 1) + next.crest.y());
        if (level_drop > 0.0) {
          report.info()[name + "_orifice_coefficient"] =
              orifice_q /
              ((weir.orifice_top - weir.floor) * std::sqrt(2.0 * gravity_ * level_drop));
        }
      }
    }
    report.value(name + "_head", head, "m");
    // The weir equation holds for a free overfall: the water downstream stays below the crest
    // (the last weir spills into the outlet, the periodic pool into its own upstream end).
    const double predicted = rehbock_discharge(head, weir.crest_height, gravity_);
    bool free_overfall = periodic_ || w + 1 == gauges_.size();
    if (!free_overfall) {
      const Weir& next = gauges_.weirs()[w + 1];
      const double downstream_level = next.crest.y() + gauges_.mean_head(w + 1);
      report.info()[name + "_downstream_level_above_crest"] = downstream_level - weir.crest.y();
      free_overfall = downstream_level < weir.crest.y();
    }
    if (free_overfall) {
      report.compare(name + "_weir_equation", q, predicted, "m^2/s",
                     fmt::format("sharp-crested weir, Rehbock C_d = 0.611 + 0.08 h/P at the "
                                 "measured head h = {:.4g} m, P = {:.4g} m",
                                 head, weir.crest_height));
    } else {
      report.info()[name + "_submerged_rehbock_discharge"] = predicted;
    }
  }
}

}  // namespace cosim::mps
