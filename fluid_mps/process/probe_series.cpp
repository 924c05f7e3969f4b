#include "probe_series.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "cosim/fluid_mps/observers.hpp"
#include "references.hpp"

namespace cosim::mps {

namespace {

constexpr double kNone = std::numeric_limits<double>::quiet_NaN();

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream in(line);
  std::string field;
  while (std::getline(in, field, ',')) fields.push_back(field);
  return fields;
}

// The sensor's name in the metrics: its column up to the unit suffix ("P1_Pa" -> "P1").
std::string sensor_name(const std::string& column) {
  return column.substr(0, column.find('_'));
}

// First time the series reaches `threshold`, interpolated between samples; NaN if never.
double first_crossing(const std::vector<double>& t, const std::vector<double>& v,
                      double threshold) {
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (v[i] < threshold) continue;
    if (i == 0) return t[0];
    const double w = (threshold - v[i - 1]) / (v[i] - v[i - 1]);
    return t[i - 1] + w * (t[i] - t[i - 1]);
  }
  return kNone;
}

double peak_in(const std::vector<double>& t, const std::vector<double>& v, double t0, double t1) {
  double peak = kNone;
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (t[i] >= t0 && t[i] <= t1) peak = std::isnan(peak) ? v[i] : std::max(peak, v[i]);
  }
  return peak;
}

// RMS(simulated - measured) / RMS(measured) at the measured times the simulation covers, the
// simulated series interpolated linearly; NaN when it covers none.
double relative_rms(const std::vector<double>& t, const std::vector<double>& v,
                    const std::vector<double>& measured_t, const std::vector<double>& measured) {
  double error = 0.0, scale = 0.0;
  int count = 0;
  std::size_t k = 1;
  for (std::size_t i = 0; i < measured_t.size(); ++i) {
    const double at = measured_t[i];
    if (t.size() < 2 || at < t.front() || at > t.back()) continue;
    while (k + 1 < t.size() && t[k] < at) ++k;
    const double w = (at - t[k - 1]) / (t[k] - t[k - 1]);
    const double simulated = v[k - 1] + w * (v[k] - v[k - 1]);
    error += (simulated - measured[i]) * (simulated - measured[i]);
    scale += measured[i] * measured[i];
    ++count;
  }
  return count > 0 && scale > 0.0 ? std::sqrt(error / scale) : kNone;
}

}  // namespace

int MeasuredTable::column(const std::string& name) const {
  const auto found = std::find(columns.begin(), columns.end(), name);
  return found == columns.end() ? -1 : static_cast<int>(found - columns.begin());
}

MeasuredTable read_measured_table(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(fmt::format("{}: cannot read", file.string()));
  MeasuredTable table;
  table.file = file;
  std::string line;
  int line_number = 0;
  bool header = false;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.empty() || line[0] == '#') continue;
    const auto fields = split(line);
    auto fail = [&](const std::string& why) {
      throw std::runtime_error(fmt::format("{}:{}: {}", file.string(), line_number, why));
    };
    if (!header) {
      if (fields.size() < 2) fail("expected a header: time, then one column a sensor");
      table.columns.assign(fields.begin() + 1, fields.end());
      table.values.resize(table.columns.size());
      header = true;
      continue;
    }
    if (fields.size() != table.columns.size() + 1) {
      fail(fmt::format("expected {} numbers, got {}", table.columns.size() + 1, fields.size()));
    }
    std::vector<double> row;
    for (const auto& field : fields) {
      std::size_t used = 0;
      double value = 0.0;
      try {
        value = std::stod(field, &used);
      } catch (const std::exception&) {
        fail(fmt::format("'{}' is not a number", field));
      }
      if (used != field.size() || !std::isfinite(value))
        fail(fmt::format("'{}' is not a number", field));
      row.push_back(value);
    }
    if (!table.times.empty() && row[0] <= table.times.back()) fail("times must increase");
    table.times.push_back(row[0]);
    for (std::size_t c = 0; c < table.columns.size(); ++c) table.values[c].push_back(row[c + 1]);
  }
  if (table.times.size() < 2) {
    throw std::runtime_error(fmt::format("{}: fewer than two samples", file.string()));
  }
  return table;
}

ProbeSeriesReport::ProbeSeriesReport(ProbeSeriesSettings settings)
    : settings_(std::move(settings)),
      pressures_(settings_.pressure_probes.size()),
      depths_(settings_.depth_gauges.size()) {}

void ProbeSeriesReport::observe(const FluidSystem& system) {
  times_.push_back(system.time());
  for (std::size_t s = 0; s < pressures_.size(); ++s) {
    pressures_[s].push_back(
        wall_pressure_at(system, settings_.pressure_probes[s].at, settings_.probe_radius));
  }
  for (std::size_t s = 0; s < depths_.size(); ++s) {
    const Eigen::Vector3d& at = settings_.depth_gauges[s].at;
    depths_[s].push_back(water_depth_at(system, at.x(), at.y(), settings_.gauge_half_width));
  }
}

void ProbeSeriesReport::report(coupler::MetricsReport& report) const {
  const MeasuredTable& m = settings_.measured;
  const double t0 = m.times.front(), t1 = m.times.back();
  const std::string source =
      fmt::format("{}, measured t in [{:.4g}, {:.4g}] s", m.file.filename().string(), t0, t1);
  auto& info = report.info();
  for (std::size_t s = 0; s < pressures_.size(); ++s) {
    const auto& sensor = settings_.pressure_probes[s];
    const auto& measured = m.values[m.column(sensor.column)];
    const std::string name = sensor_name(sensor.column);
    const double measured_peak = peak_in(m.times, measured, t0, t1);
    const double threshold = settings_.arrival_fraction * measured_peak;
    const double measured_arrival = first_crossing(m.times, measured, threshold);
    const double arrival = first_crossing(times_, pressures_[s], threshold);
    // Arrival is compared with the time from release (relative error) and given in ms too.
    if (std::isnan(arrival)) {
      info[name + "_arrival"] = "not reached";
    } else {
      report.compare(
          name + "_arrival_time", arrival, measured_arrival, "s",
          fmt::format("{}: first {:.3g} of the measured peak", source, settings_.arrival_fraction));
      info[name + "_arrival_delay_ms"] = 1e3 * (arrival - measured_arrival);
    }
    const double peak = peak_in(times_, pressures_[s], t0, t1);
    if (!std::isnan(peak)) {
      report.compare(name + "_peak_pressure", peak, measured_peak, "Pa", source);
    }
    const double rms = relative_rms(times_, pressures_[s], m.times, measured);
    if (!std::isnan(rms)) report.error(name + "_pressure_error", rms, source);
  }
  for (std::size_t s = 0; s < depths_.size(); ++s) {
    const auto& sensor = settings_.depth_gauges[s];
    const auto& measured = m.values[m.column(sensor.column)];
    const double rms = relative_rms(times_, depths_[s], m.times, measured);
    if (!std::isnan(rms)) report.error(sensor_name(sensor.column) + "_depth_error", rms, source);
  }
}

std::vector<ReferenceSeries> ProbeSeriesReport::series() const {
  const MeasuredTable& m = settings_.measured;
  const std::string source = m.file.filename().string();
  std::vector<ReferenceSeries> out;
  auto add = [&](const ProbeSeriesSettings::Sensor& sensor, const std::vector<double>& values,
                 const std::string& prefix, const std::string& unit, const std::string& what) {
    const Eigen::Vector3d& x = sensor.at;
    out.push_back({prefix + sensor_name(sensor.column), unit,
                   fmt::format("{} at ({:.4g}, {:.4g}, {:.4g}) m", what, x.x(), x.y(), x.z()),
                   source, times_, values, m.times, m.values[m.column(sensor.column)]});
  };
  for (std::size_t s = 0; s < pressures_.size(); ++s) {
    add(settings_.pressure_probes[s], pressures_[s], "pressure_", "Pa",
        "mean pressure of fluid and wall particles near the sensor");
  }
  for (std::size_t s = 0; s < depths_.size(); ++s) {
    add(settings_.depth_gauges[s], depths_[s], "depth_", "m", "water depth at the gauge");
  }
  return out;
}

}  // namespace cosim::mps
