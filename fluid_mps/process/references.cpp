#include "references.hpp"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "cosim/fluid_mps/scenes.hpp"

namespace cosim::mps {

namespace {

// Linear interpolation of a sampled series; nothing outside it.
bool interpolate(const std::vector<double>& x, const std::vector<double>& y, double at,
                 double& value) {
  if (x.empty() || at < x.front() || at > x.back()) return false;
  for (std::size_t i = 1; i < x.size(); ++i) {
    if (at <= x[i]) {
      const double w = x[i] > x[i - 1] ? (at - x[i - 1]) / (x[i] - x[i - 1]) : 1.0;
      value = y[i - 1] + w * (y[i] - y[i - 1]);
      return true;
    }
  }
  value = y.back();
  return true;
}

}  // namespace

ReferenceTracker::ReferenceTracker(const ReferenceSettings& settings, double gravity)
    : settings_(settings), gravity_(gravity) {
  if (settings_.kind == "martin_moyce") {
    std::ifstream in(settings_.file);
    std::string line;
    int line_number = 0;
    while (std::getline(in, line)) {
      ++line_number;
      if (line.empty() || line[0] == '#' || line.rfind("kind", 0) == 0) continue;
      std::stringstream fields(line);
      std::string kind, x, y;
      std::getline(fields, kind, ',');
      std::getline(fields, x, ',');
      std::getline(fields, y, ',');
      try {
        Curve& curve = kind == "front" ? front_reference_ : height_reference_;
        if (kind != "front" && kind != "height") throw std::invalid_argument(kind);
        curve.x.push_back(std::stod(x));
        curve.y.push_back(std::stod(y));
      } catch (const std::exception&) {
        throw std::runtime_error(fmt::format("{}:{}: expected 'front|height,x,y', got '{}'",
                                             settings_.file.string(), line_number, line));
      }
    }
  } else {
    pressure_sums_.assign(settings_.probe_depths.size(), 0.0);
  }
}

void ReferenceTracker::observe(const FluidSystem& system) {
  last_time_ = system.time();
  density_ = system.parameters().density;
  if (settings_.kind == "martin_moyce") {
    times_.push_back(system.time());
    fronts_.push_back(surge_front_position(system));
    heights_.push_back(residual_column_height(system));
    return;
  }
  if (system.time() < settings_.average_from) return;
  const double radius = settings_.probe_radius;
  for (std::size_t i = 0; i < settings_.probe_depths.size(); ++i) {
    const Eigen::Vector3d probe(settings_.probe_x,
                                settings_.still_depth - settings_.probe_depths[i], 0.0);
    pressure_sums_[i] += mean_pressure_at(system, probe, radius);
  }
  ++pressure_samples_;
}

void ReferenceTracker::report(coupler::MetricsReport& report) const {
  if (settings_.kind == "martin_moyce") {
    const double a = settings_.column_width;
    const std::string source = "Martin & Moyce (1952), n^2 = 2";
    auto rms_against = [&](const Curve& reference, const std::vector<double>& observed,
                           double time_scale, double length_scale, const std::string& name) {
      double sum = 0.0, reference_sum = 0.0;
      int count = 0;
      std::vector<double> dimensionless_times;
      for (double t : times_) dimensionless_times.push_back(t * time_scale);
      for (std::size_t i = 0; i < reference.x.size(); ++i) {
        double simulated = 0.0;
        if (!interpolate(dimensionless_times, observed, reference.x[i], simulated)) continue;
        const double error = simulated / length_scale - reference.y[i];
        sum += error * error;
        reference_sum += reference.y[i] * reference.y[i];
        ++count;
      }
      if (count == 0) return;
      // Relative RMS error: RMS(simulated - measured) / RMS(measured) over the measured points
      // inside the simulated time.
      report.error(name, std::sqrt(sum / count) / std::sqrt(reference_sum / count), source);
      report.info()[name + "_points"] = count;
    };
    rms_against(front_reference_, fronts_, std::sqrt(2 * gravity_ / a), a, "surge_front_error");
    rms_against(height_reference_, heights_, std::sqrt(gravity_ / a), 2 * a,
                "residual_height_error");
    return;
  }
  for (std::size_t i = 0; i < settings_.probe_depths.size(); ++i) {
    const double depth = settings_.probe_depths[i];
    const double mean = pressure_samples_ > 0 ? pressure_sums_[i] / pressure_samples_ : 0.0;
    report.compare(fmt::format("pressure_at_depth_{:.4g}m", depth), mean,
                   density_ * gravity_ * depth, "Pa",
                   fmt::format("rho g depth, time average from {:.3g} s", settings_.average_from));
  }
}

}  // namespace cosim::mps
