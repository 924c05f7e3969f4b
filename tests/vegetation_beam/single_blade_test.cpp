// Single submerged blade in a uniform stream, the set-up of seed 000 section 3(2) (Kitamura's
// OHP-sheet strip): L = 0.045 m, b = 0.002 m, t = 1.2e-4 m, EI = 8.67e-7 N m^2, density of
// water. Checks that the bent equilibrium is reached and is physically sensible; it is not
// tuned to the paper's figure.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "beam_test_helpers.hpp"

namespace cosim::vegetation {
namespace {

struct BladeResult {
  double tip_x = 0, tip_y = 0;          // tip displacement, m
  double upright_drag = 0;              // drag on the upright blade held still, N
  double final_drag = 0;                // drag at equilibrium, N
  double final_frozen_drag = 0;         // drag on the final shape held still, N
  bool drag_falls_with_bending = true;  // over snapshots: more tip deflection, less drag
  double final_tip_speed = 0;           // m/s
  double max_axial_strain = 0;
  double time = 0;  // s simulated
};

PlantSpec kitamura_blade() {
  PlantSpec blade;
  blade.length = 0.045;
  blade.links = 12;
  blade.width = 0.002;
  blade.thickness = 1.2e-4;
  blade.bending_stiffness = 8.67e-7;
  // E from EI of the rectangular section; EA follows from it (OHP sheet, about 3 GPa).
  blade.youngs_modulus =
      12 * blade.bending_stiffness / (blade.width * std::pow(blade.thickness, 3));
  blade.density = 1000;
  return blade;
}

// Drag the stream exerts on a shape held still (rigid mode), N along the stream.
double frozen_drag(const std::vector<Eigen::Vector3d>& shape, double stream_speed) {
  BeamParameters parameters;
  parameters.rigid = true;
  PlantField frozen({kitamura_blade()}, parameters);
  frozen.set_state(shape, std::vector<Eigen::Vector3d>(shape.size(), Eigen::Vector3d::Zero()));
  const auto flow = testing::uniform(frozen, Eigen::Vector3d(stream_speed, 0, 0));
  frozen.advance(1e-4, flow, flow);
  double drag = 0;
  for (const auto& f : frozen.window_mean_drag()) drag += f.x();
  return drag;
}

BladeResult run_blade(double stream_speed, double safety_factor = 0.5) {
  const PlantSpec blade = kitamura_blade();
  BeamParameters parameters;  // water, C_D = 1, C_M = 1, seed-style dashpots
  parameters.safety_factor = safety_factor;
  PlantField field({blade}, parameters);
  const auto flow = testing::uniform(field, Eigen::Vector3d(stream_speed, 0, 0));
  const double window = 5e-4;  // the seed's fluid step
  BladeResult result;
  result.upright_drag = frozen_drag(field.positions(), stream_speed);
  std::vector<std::pair<double, double>> snapshots;  // (tip deflection, frozen drag)
  double previous_drag = 0;
  for (int w = 0; w < 2000; ++w) {
    field.advance(window, flow, flow);
    double drag = 0;
    for (const auto& f : field.window_mean_drag()) drag += f.x();
    const double change = std::abs(drag - previous_drag);
    previous_drag = drag;
    if (w % 40 == 0)
      snapshots.emplace_back(field.tip_displacement(0).x(),
                             frozen_drag(field.positions(), stream_speed));
    // Steady: drag changes by less than 1e-5 of itself per window and the tip speed is below
    // 1e-4 of the stream's.
    const double tip_speed = field.velocities().back().norm();
    if (w > 10 && change < 1e-5 * drag && tip_speed < 1e-4 * stream_speed) break;
  }
  std::sort(snapshots.begin(), snapshots.end());
  for (std::size_t i = 1; i < snapshots.size(); ++i)
    if (snapshots[i].second > snapshots[i - 1].second) result.drag_falls_with_bending = false;
  result.final_drag = previous_drag;
  result.final_frozen_drag = frozen_drag(field.positions(), stream_speed);
  result.tip_x = field.tip_displacement(0).x();
  result.tip_y = field.tip_displacement(0).y();
  result.final_tip_speed = field.velocities().back().norm();
  const double l0 = blade.length / blade.links;
  for (int i = 1; i < field.node_count(); ++i) {
    const double strain = (field.positions()[i] - field.positions()[i - 1]).norm() / l0 - 1;
    result.max_axial_strain = std::max(result.max_axial_strain, std::abs(strain));
  }
  result.time = field.time();
  return result;
}

// Default-parameter runs are shared by the tests below (each takes seconds).
const BladeResult& default_run(double stream_speed) {
  static std::map<double, BladeResult> runs;
  auto it = runs.find(stream_speed);
  if (it == runs.end()) it = runs.emplace(stream_speed, run_blade(stream_speed)).first;
  return it->second;
}

TEST(SingleBlade, ReachesSensibleBentEquilibriumInUniformStream) {
  const double length = 0.045;
  const BladeResult& slow = default_run(0.1);
  const BladeResult& fast = default_run(0.2);
  for (const auto& [speed, r] : {std::pair{0.1, slow}, std::pair{0.2, fast}}) {
    std::printf(
        "U = %.2f m/s: steady after %.3f s, tip (%.4f, %.4f) m = (%.3f, %.3f) L, drag "
        "%.4e N -> %.4e N (upright 0.5 rho C_D b L U^2 = %.4e N), strain %.1e\n",
        speed, r.time, r.tip_x, r.tip_y, r.tip_x / length, r.tip_y / length, r.upright_drag,
        r.final_drag, 0.5 * 1000 * 0.002 * length * speed * speed, r.max_axial_strain);
    EXPECT_LT(r.time, 0.99) << "steady state not reached within 2000 windows";
    EXPECT_LT(r.final_tip_speed, 2e-4 * speed);
    // Bent downstream and down, but never beyond its length.
    EXPECT_GT(r.tip_x, 0);
    EXPECT_LT(r.tip_x, length);
    EXPECT_LT(r.tip_y, 0);
    EXPECT_GT(r.tip_y, -length);
    // Drag falls as the blade bends (reconfiguration), starting from the upright value.
    EXPECT_NEAR(r.upright_drag, 0.5 * 1000 * 0.002 * length * speed * speed, 1e-9 * r.upright_drag);
    EXPECT_TRUE(r.drag_falls_with_bending);
    EXPECT_LT(r.final_drag, r.upright_drag);
    EXPECT_GT(r.final_drag, 0);
    EXPECT_NEAR(r.final_drag, r.final_frozen_drag, 1e-3 * r.final_drag) << "not at rest";
    // Seed: axial strain is practically zero at steady state.
    EXPECT_LT(r.max_axial_strain, 1e-4);
  }
  // A faster stream bends the blade further, and drag grows more slowly than U^2.
  EXPECT_GT(fast.tip_x, slow.tip_x);
  EXPECT_LT(fast.final_drag / slow.final_drag, 4.0);
}

}  // namespace
}  // namespace cosim::vegetation

namespace cosim::vegetation {
namespace {

// Newmark average acceleration is unconditionally stable for linear problems: sub-steps 40 times
// the axial spring-mass limit still converge (Newton) to the same equilibrium.
TEST(SingleBlade, LargeSubstepsReachTheSameEquilibrium) {
  const BladeResult& reference = default_run(0.2);
  const BladeResult coarse = run_blade(0.2, 20.0);
  std::printf("tip x: safety 0.5 %.7f m, safety 20 %.7f m\n", reference.tip_x, coarse.tip_x);
  EXPECT_NEAR(coarse.tip_x, reference.tip_x, 1e-4 * reference.tip_x);
  EXPECT_NEAR(coarse.tip_y, reference.tip_y, 1e-3 * std::abs(reference.tip_y));
}

}  // namespace
}  // namespace cosim::vegetation
