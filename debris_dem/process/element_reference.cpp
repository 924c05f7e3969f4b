#include "element_reference.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "cosim/debris_dem/fluid_forces.hpp"

namespace cosim::dem {

namespace {

constexpr double kPi = std::numbers::pi;

// Root of a monotone increasing f on [low, high] by bisection (f(low) < 0 < f(high)).
template <class F>
double bisect(F f, double low, double high) {
  for (int i = 0; i < 200 && high - low > 1e-15 * std::max(1.0, high); ++i) {
    const double mid = 0.5 * (low + high);
    (f(mid) < 0.0 ? low : high) = mid;
  }
  return 0.5 * (low + high);
}

double mean_from(const std::vector<double>& times, const std::vector<double>& values, double from) {
  double sum = 0.0;
  int count = 0;
  for (std::size_t i = 0; i < times.size(); ++i) {
    if (times[i] < from || !std::isfinite(values[i])) continue;
    sum += values[i];
    ++count;
  }
  return count > 0 ? sum / count : std::nan("");
}

}  // namespace

double schiller_naumann_terminal_velocity(double diameter, double solid_density,
                                          double fluid_density, double viscosity, double gravity) {
  if (!(solid_density > fluid_density)) {
    throw std::invalid_argument("terminal velocity: the sphere is not heavier than the liquid");
  }
  const double volume = kPi * diameter * diameter * diameter / 6.0;
  const double area = 0.25 * kPi * diameter * diameter;
  const double weight = (solid_density - fluid_density) * gravity * volume;
  auto excess_drag = [&](double v) {
    const double reynolds = fluid_density * v * diameter / viscosity;
    return 0.5 * fluid_density * schiller_naumann_drag_coefficient(reynolds) * area * v * v -
           weight;
  };
  double high = 1.0;
  while (excess_drag(high) < 0.0) high *= 2.0;
  return bisect(excess_drag, 1e-12, high);
}

double floating_cylinder_draft(double diameter, double density_ratio) {
  if (!(density_ratio > 0.0 && density_ratio < 1.0)) {
    throw std::invalid_argument("floating draft: the density ratio must lie in (0, 1)");
  }
  const double theta = bisect(
      [&](double t) { return (t - std::sin(t)) / (2.0 * kPi) - density_ratio; }, 0.0, 2.0 * kPi);
  return 0.5 * diameter * (1.0 - std::cos(0.5 * theta));
}

double floating_sphere_draft(double diameter, double density_ratio) {
  const double r = 0.5 * diameter;
  return bisect([&](double h) { return sphere_submerged_fraction(r, r, h) - density_ratio; }, 0.0,
                diameter);
}

ElementReference::ElementReference(ElementReferenceSettings settings, double reference_value,
                                   double radius)
    : settings_(std::move(settings)), reference_(reference_value), radius_(radius) {}

void ElementReference::observe(double time, const Eigen::Vector3d& center,
                               const Eigen::Vector3d& velocity, double surface) {
  times_.push_back(time);
  heights_.push_back(center.z());
  vertical_.push_back(velocity.z());
  drafts_.push_back(std::isfinite(surface) ? surface - (center.z() - radius_) : std::nan(""));
}

void ElementReference::report(coupler::MetricsReport& report) const {
  if (settings_.kind == ReferenceKind::settling) report_settling(report);
  if (settings_.kind == ReferenceKind::floating) report_floating(report);
}

void ElementReference::report_settling(coupler::MetricsReport& report) const {
  // The settling speed once the transient has passed (the mean over the averaging window).
  const double speed = -mean_from(times_, vertical_, settings_.average_from);
  report.compare("terminal_velocity", speed, reference_, "m/s",
                 "Schiller & Naumann (1933) drag, the same sphere and liquid, unbounded");
  double fastest = 0.0;
  for (const double w : vertical_) fastest = std::max(fastest, -w);
  report.value("fastest_settling_speed", fastest, "m/s");
}

void ElementReference::report_floating(coupler::MetricsReport& report) const {
  const double draft = mean_from(times_, drafts_, settings_.average_from);
  if (!std::isfinite(draft)) {
    // Out of the water (or no water below it) over the whole averaging window.
    report.info()["draft_problem"] = "the element was never afloat after average_from";
    return;
  }
  report.compare("draft", draft, reference_, "m",
                 "Archimedes: submerged share equals the density ratio");
  report_heave(report);
}

void ElementReference::report_heave(coupler::MetricsReport& report) const {
  // Heave about the settled height (the mean z over the averaging window), smoothed over
  // +-10 ms. A period runs from one upward crossing to the next; its amplitude is its largest
  // excursion. The decay per period is the geometric mean of successive amplitude ratios over
  // the first five periods after the element first touched the water.
  const double settled = mean_from(times_, heights_, settings_.average_from);
  std::size_t first_wet = 0;
  while (first_wet < drafts_.size() &&
         !(std::isfinite(drafts_[first_wet]) && drafts_[first_wet] > 0.0)) {
    ++first_wet;
  }
  if (!std::isfinite(settled) || first_wet + 2 >= times_.size()) return;
  std::vector<double> deviation(times_.size(), 0.0);
  std::size_t low = first_wet, high = first_wet;  // window [low, high) of times within 10 ms
  double sum = 0.0;
  for (std::size_t i = first_wet; i < times_.size(); ++i) {
    while (high < times_.size() && times_[high] <= times_[i] + 0.01) sum += heights_[high++];
    while (times_[low] < times_[i] - 0.01) sum -= heights_[low++];
    deviation[i] = sum / static_cast<double>(high - low) - settled;
  }
  // RMS heave over the first second in the water and over the averaging window.
  auto rms = [&](double from, double to) {
    double sum = 0.0;
    int count = 0;
    for (std::size_t i = first_wet; i < times_.size(); ++i) {
      if (times_[i] < from || times_[i] > to) continue;
      sum += deviation[i] * deviation[i];
      ++count;
    }
    return count > 0 ? std::sqrt(sum / count) : std::nan("");
  };
  const double early = rms(times_[first_wet], times_[first_wet] + 1.0);
  const double late = rms(settings_.average_from, times_.back());
  report.value("heave_rms_first_second", early, "m");
  report.value("heave_rms_averaging_window", late, "m");
  // Periods between upward crossings, each counted only after the heave went below -h
  // (h = half the late RMS): jitter around the settled height makes no crossings.
  const double h = 0.5 * late;
  std::vector<double> crossings, amplitudes;
  double largest = 0.0;
  bool below = false;
  for (std::size_t i = first_wet + 1; i < times_.size(); ++i) {
    largest = std::max(largest, std::abs(deviation[i]));
    if (deviation[i] < -h) below = true;
    if (below && deviation[i] >= h) {
      if (!crossings.empty()) amplitudes.push_back(largest);
      crossings.push_back(times_[i]);
      largest = 0.0;
      below = false;
    }
  }
  report.info()["heave_periods"] = amplitudes.size();
  if (amplitudes.size() < 2) return;
  const std::size_t last = std::min<std::size_t>(amplitudes.size() - 1, 5);
  report.value("heave_decay_ratio", std::pow(amplitudes[last] / amplitudes[0], 1.0 / last), "");
  std::vector<double> periods;
  for (std::size_t k = 1; k < crossings.size(); ++k) {
    periods.push_back(crossings[k] - crossings[k - 1]);
  }
  std::nth_element(periods.begin(), periods.begin() + periods.size() / 2, periods.end());
  report.value("heave_period", periods[periods.size() / 2], "s");  // median
}

double richardson_zaki_exponent(double re) {
  if (re < 0.2) return 4.65;
  if (re < 1.0) return 4.4 * std::pow(re, -0.03);
  if (re < 500.0) return 4.4 * std::pow(re, -0.1);
  return 2.4;
}

SuspensionReference::SuspensionReference(double average_from, double phi, double terminal_velocity,
                                         double terminal_reynolds)
    : average_from_(average_from),
      phi_(phi),
      terminal_velocity_(terminal_velocity),
      reynolds_(terminal_reynolds) {}

void SuspensionReference::observe(double time, const Eigen::Vector3d& mean_velocity) {
  if (time < average_from_) return;
  sum_ -= mean_velocity.z();
  ++count_;
}

void SuspensionReference::report(coupler::MetricsReport& report) const {
  const double n = richardson_zaki_exponent(reynolds_);
  const double speed = count_ > 0 ? sum_ / count_ : std::nan("");
  report.compare("hindered_settling_velocity", speed, terminal_velocity_ * std::pow(1.0 - phi_, n),
                 "m/s",
                 fmt::format("Richardson & Zaki (1954), phi = {:.4g}, n = {:.3g} at Re_t = {:.3g}",
                             phi_, n, reynolds_));
  report.value("settling_over_terminal_velocity", speed / terminal_velocity_, "");
  report.info()["solid_fraction"] = phi_;
  report.info()["single_sphere_terminal_velocity"] = terminal_velocity_;
}

}  // namespace cosim::dem
