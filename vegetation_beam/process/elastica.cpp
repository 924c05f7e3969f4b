#include "elastica.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace cosim::vegetation {

namespace {

// State along the plant from the tip: angle theta from the unstressed direction, the resultant
// (streamwise, upward) load on the part beyond s, and the bending moment there.
struct State {
  double theta, force_x, force_y, moment;
};

State derivative(const ElasticaProblem& p, const State& y) {
  const double tangent_x = std::sin(y.theta), tangent_y = std::cos(y.theta);
  // Normal relative velocity: U cos(theta) along (cos theta, -sin theta); drag |u_n| u_n.
  const double normal_speed = p.speed * std::cos(y.theta);
  const double drag =
      0.5 * p.fluid_density * p.drag_coefficient * p.width * normal_speed * std::abs(normal_speed);
  const double buoyancy = (p.fluid_density - p.plant_density) * p.gravity * p.width * p.thickness;
  const double load_x = drag * std::cos(y.theta);
  const double load_y = -drag * std::sin(y.theta) + buoyancy;
  State dy;
  dy.force_x = -load_x;
  dy.force_y = -load_y;
  dy.moment = -(tangent_x * y.force_y - tangent_y * y.force_x);
  dy.theta = -y.moment / p.bending_stiffness;
  return dy;
}

State add(const State& y, const State& dy, double h) {
  return {y.theta + h * dy.theta, y.force_x + h * dy.force_x, y.force_y + h * dy.force_y,
          y.moment + h * dy.moment};
}

// Integrates from the tip (angle tip_angle, no load, no moment) to the base with RK4. Returns
// the base angle; fills the tip position and the shape when asked.
double shoot(const ElasticaProblem& p, double tip_angle, ElasticaSolution* solution) {
  const double h = -p.length / p.steps;
  State y{tip_angle, 0.0, 0.0, 0.0};
  // Shape from the tip, positions relative to the tip until the base is known.
  std::vector<ElasticaPoint> from_tip;
  if (solution) from_tip.reserve(p.steps + 1);
  double streamwise = 0.0, height = 0.0;
  if (solution) from_tip.push_back({p.length, tip_angle, 0.0, 0.0});
  for (int step = 0; step < p.steps; ++step) {
    const State k1 = derivative(p, y);
    const State k2 = derivative(p, add(y, k1, h / 2));
    const State k3 = derivative(p, add(y, k2, h / 2));
    const State k4 = derivative(p, add(y, k3, h));
    const State next{
        y.theta + h / 6 * (k1.theta + 2 * k2.theta + 2 * k3.theta + k4.theta),
        y.force_x + h / 6 * (k1.force_x + 2 * k2.force_x + 2 * k3.force_x + k4.force_x),
        y.force_y + h / 6 * (k1.force_y + 2 * k2.force_y + 2 * k3.force_y + k4.force_y),
        y.moment + h / 6 * (k1.moment + 2 * k2.moment + 2 * k3.moment + k4.moment)};
    // Tip position relative to the base: integral of the tangent (trapezoid).
    streamwise += -h * 0.5 * (std::sin(y.theta) + std::sin(next.theta));
    height += -h * 0.5 * (std::cos(y.theta) + std::cos(next.theta));
    y = next;
    if (solution) from_tip.push_back({p.length + (step + 1) * h, y.theta, -streamwise, -height});
  }
  if (solution) {
    solution->tip_streamwise = streamwise;
    solution->tip_height = height;
    solution->tip_angle = tip_angle;
    solution->shape.assign(from_tip.rbegin(), from_tip.rend());
    for (ElasticaPoint& point : solution->shape) {
      point.streamwise += streamwise;
      point.height += height;
    }
    solution->shape.front().s = 0.0;
  }
  return y.theta;
}

}  // namespace

bool is_monotone(const std::vector<ElasticaPoint>& shape, double tolerance) {
  double highest = -std::numeric_limits<double>::infinity();
  for (const ElasticaPoint& point : shape) {
    if (point.angle < highest - tolerance) return false;
    highest = std::max(highest, point.angle);
  }
  return true;
}

ElasticaSolution solve_elastica(const ElasticaProblem& problem) {
  if (problem.length <= 0 || problem.bending_stiffness <= 0 || problem.steps < 10) {
    throw std::runtime_error(
        "elastica reference: length, bending stiffness and steps must be positive");
  }
  // The base angle must be 0 (clamped): find the tip angles where it changes sign. Above a
  // Cauchy number Ca = rho C_D b U^2 L^3 / (2 EI) of about 100 there are several, and the
  // smallest tip angle belongs to a shape that swings back against the stream (measured: Ca 300
  // has 3 clamped equilibria, Ca 3000 has 7, only the one with the largest tip angle is
  // monotone). The monotone tip angle approaches pi/2 as Ca grows (pi/2 - 0.114 at Ca 300,
  // - 0.020 at Ca 3000, - 0.0067 at Ca 1e4) and neighbouring roots crowd there, so the scan
  // is geometric in pi/2 - angle (5.9 % steps from pi/2 * 1e-9 up to pi/2, good past
  // Ca 1e10) and walks down from the top, keeping the first monotone equilibrium.
  const double quarter = std::numbers::pi / 2;
  constexpr int scan = 360;
  constexpr double smallest_gap = 1e-9;  // of pi/2
  auto angle_at = [&](int i) {           // i = 0 near pi/2, i = scan: 0
    return i == scan ? 0.0 : quarter * (1 - std::pow(smallest_gap, 1.0 - double(i) / scan));
  };
  ElasticaSolution solution;
  int rejected = 0;
  auto accept = [&](double tip_angle) {
    ElasticaSolution candidate;
    shoot(problem, tip_angle, &candidate);
    if (!is_monotone(candidate.shape)) {
      ++rejected;
      return false;
    }
    solution = std::move(candidate);
    return true;
  };
  double high = angle_at(0);
  double residual_high = shoot(problem, high, nullptr);
  if (residual_high == 0.0 && accept(high)) return solution;
  for (int i = 1; i <= scan; ++i) {
    const double low = angle_at(i);
    const double residual_low = shoot(problem, low, nullptr);
    if (residual_low == 0.0) {
      if (accept(low)) return solution;
    } else if ((residual_low < 0) != (residual_high < 0) && residual_high != 0.0) {
      double a = low, b = high, fa = residual_low;
      for (int iteration = 0; iteration < 200 && b - a > 1e-15; ++iteration) {
        const double m = 0.5 * (a + b);
        const double fm = shoot(problem, m, nullptr);
        if ((fm < 0) == (fa < 0)) {
          a = m;
          fa = fm;
        } else {
          b = m;
        }
      }
      if (accept(0.5 * (a + b))) return solution;
    }
    high = low;
    residual_high = residual_low;
  }
  throw std::runtime_error(
      "elastica reference: no monotone clamped equilibrium with a tip angle below 90 degrees (" +
      std::to_string(rejected) + " non-monotone ones found)");
}

}  // namespace cosim::vegetation
