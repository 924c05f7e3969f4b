// Emergent plants: drag and buoyancy act only on the submerged share of each node.
#include <gtest/gtest.h>

#include "beam_test_helpers.hpp"

namespace cosim::vegetation {
namespace {

PlantSpec blade() {
  PlantSpec spec;
  spec.length = 0.1;
  spec.links = 10;
  spec.width = 0.005;
  spec.thickness = 0.001;
  spec.youngs_modulus = 1e9;
  spec.density = 500;
  return spec;
}

Eigen::Vector3d total(const std::vector<Eigen::Vector3d>& forces) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const auto& force : forces) sum += force;
  return sum;
}

TEST(WaterFraction, DragActsOnTheSubmergedNodesOnly) {
  BeamParameters parameters;
  parameters.rigid = true;
  parameters.gravity.setZero();
  PlantField wet({blade()}, parameters);
  PlantField half({blade()}, parameters);
  const auto flow = testing::uniform(wet, {0.3, 0.0, 0.0});
  // Nodes 0-5 submerged (the lower half), 6-10 in air.
  std::vector<double> fraction(half.node_count(), 0.0);
  for (int k = 0; k <= 5; ++k) fraction[k] = 1.0;
  half.set_water_fraction(fraction);
  wet.advance(1e-3, flow, flow);
  half.advance(1e-3, flow, flow);
  const double full_drag = total(wet.window_mean_drag()).x();
  const double half_drag = total(half.window_mean_drag()).x();
  // Lumped lengths: nodes 0..5 carry 0.5 + 5 = 5.5 of the 10 links.
  EXPECT_NEAR(half_drag / full_drag, 0.55, 1e-12);
  for (int k = 6; k <= 10; ++k) EXPECT_EQ(half.window_mean_drag()[k].norm(), 0.0);
}

TEST(WaterFraction, ADryPlantIsNotBuoyed) {
  // A light plant (500 kg/m3) floats upright in water but droops in air.
  BeamParameters parameters;
  parameters.bending_damping_ratio = 1.0;
  PlantSpec spec = blade();
  spec.youngs_modulus = 1e6;  // soft enough to bend under its own weight
  spec.direction = Eigen::Vector3d(1.0, 1.0, 0.0).normalized();
  PlantField wet({spec}, parameters);
  PlantField dry({spec}, parameters);
  dry.set_water_fraction(std::vector<double>(dry.node_count(), 0.0));
  const auto still = testing::uniform(wet, Eigen::Vector3d::Zero());
  for (int window = 0; window < 200; ++window) {
    wet.advance(2e-3, still, still);
    dry.advance(2e-3, still, still);
  }
  EXPECT_GT(wet.tip_displacement(0).y(), 0.0) << "net buoyancy lifts the tip in water";
  EXPECT_LT(dry.tip_displacement(0).y(), 0.0) << "its weight pulls the tip down in air";
}

TEST(WaterFraction, RejectsAWrongSize) {
  PlantField field({blade()}, BeamParameters{});
  EXPECT_THROW(field.set_water_fraction({1.0, 0.5}), std::invalid_argument);
}

}  // namespace
}  // namespace cosim::vegetation
