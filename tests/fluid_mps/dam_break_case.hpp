// Martin & Moyce (1952) dam break, n^2 = 2, a = 0.05715 m, run at one resolution and compared
// with references/martin_moyce_1952.csv.
#pragma once

#include <chrono>
#include <cmath>
#include <ctime>
#include <fstream>
#include <functional>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/scenes.hpp"

namespace cosim::mps::testing {

struct ReferencePoint {
  double time;   // dimensionless T (front) or tau (height)
  double value;  // Z or H
};

struct MartinMoyce {
  std::vector<ReferencePoint> front, height;
};

inline MartinMoyce read_martin_moyce(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  MartinMoyce data;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line.rfind("kind", 0) == 0) continue;
    std::stringstream ss(line);
    std::string kind, x, y;
    std::getline(ss, kind, ',');
    std::getline(ss, x, ',');
    std::getline(ss, y, ',');
    (kind == "front" ? data.front : data.height).push_back({std::stod(x), std::stod(y)});
  }
  return data;
}

struct DamBreakResult {
  double l0 = 0.0;
  int particles = 0;
  long steps = 0;
  double wall_seconds = 0.0;
  double cpu_seconds = 0.0;  // process CPU time (all threads): robust to a loaded machine
  double front_rms = 0.0;    // relative RMS error of Z over reference points inside the run
  double height_rms = 0.0;   // relative RMS error of H
  int front_points = 0, height_points = 0;
  double mean_pcg_iterations = 0.0;
};

// Linear interpolation of a sampled history at time t.
inline double interpolate(const std::vector<double>& times, const std::vector<double>& values,
                          double t) {
  for (std::size_t k = 1; k < times.size(); ++k) {
    if (times[k] >= t) {
      const double s = (t - times[k - 1]) / (times[k] - times[k - 1]);
      return values[k - 1] + s * (values[k] - values[k - 1]);
    }
  }
  return values.back();
}

inline MpsParameters dam_break_parameters(double l0) {
  MpsParameters p;
  p.particle_spacing = l0;
  p.max_dt = 0.25 * l0 / std::sqrt(9.81 * 2.0 * 0.05715);  // CFL on the final front speed
  return p;
}

inline DamBreakResult run_dam_break(int cells_per_width, double end_time,
                                    const std::string& reference_path,
                                    const std::function<void(MpsParameters&)>& tune = {}) {
  const double a = 0.05715, g = 9.81;
  const double l0 = a / cells_per_width;
  MpsParameters p = dam_break_parameters(l0);
  if (tune) tune(p);
  ParticleSet particles = dam_break(p, a, 2.0 * a, 8.0 * a, 3.0 * a);
  FluidSystem system(p, std::move(particles));
  std::vector<double> times{0.0}, fronts{surge_front_position(system)},
      heights{residual_column_height(system)};
  const auto start = std::chrono::steady_clock::now();
  const std::clock_t cpu_start = std::clock();
  long pcg_total = 0;
  while (system.time() < end_time) {
    const StepReport report = system.step(system.stable_dt());
    pcg_total += report.pcg_iterations;
    times.push_back(system.time());
    fronts.push_back(surge_front_position(system));
    heights.push_back(residual_column_height(system));
  }
  DamBreakResult result;
  result.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.cpu_seconds = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
  result.l0 = l0;
  result.particles = system.particle_count();
  result.steps = system.step_count();
  result.mean_pcg_iterations = static_cast<double>(pcg_total) / std::max(1L, result.steps);
  const MartinMoyce reference = read_martin_moyce(reference_path);
  std::ostringstream detail;
  double sum = 0.0;
  for (const auto& point : reference.front) {
    const double t = point.time / std::sqrt(2.0 * g / a);
    if (t > end_time) continue;
    const double z = interpolate(times, fronts, t) / a;
    sum += std::pow((z - point.value) / point.value, 2);
    ++result.front_points;
    detail << "  front T=" << point.time << " Z_ref=" << point.value << " Z_mps=" << z << "\n";
  }
  result.front_rms = std::sqrt(sum / std::max(1, result.front_points));
  sum = 0.0;
  for (const auto& point : reference.height) {
    const double t = point.time / std::sqrt(g / a);
    if (t > end_time) continue;
    const double h = interpolate(times, heights, t) / (2.0 * a);
    sum += std::pow((h - point.value) / point.value, 2);
    ++result.height_points;
    detail << "  height tau=" << point.time << " H_ref=" << point.value << " H_mps=" << h << "\n";
  }
  result.height_rms = std::sqrt(sum / std::max(1, result.height_points));
  std::cout << "[dam break] a/l0=" << cells_per_width << " particles=" << result.particles
            << " steps=" << result.steps << " wall=" << result.wall_seconds
            << " s cpu=" << result.cpu_seconds << " s"
            << " front_rms=" << 100.0 * result.front_rms << " % (" << result.front_points
            << " pts) height_rms=" << 100.0 * result.height_rms << " % (" << result.height_points
            << " pts) mean_pcg=" << result.mean_pcg_iterations << "\n"
            << detail.str();
  return result;
}

}  // namespace cosim::mps::testing
