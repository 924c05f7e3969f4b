// A plant field saved mid-run and loaded into a field built from the same specs continues with
// the same bits as the one that ran on, contacts, water fraction and coupling forces included.
#include <gtest/gtest.h>

#include <cstring>

#include "cosim/vegetation_beam/checkpoint.hpp"

namespace cosim::vegetation {
namespace {

bool same_bits(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0;
}

PlantField make_field() {
  PlantSpec a;
  a.length = 0.1;
  a.links = 12;
  a.width = 0.01;
  a.thickness = 0.002;
  a.youngs_modulus = 1e8;
  a.density = 900;
  a.direction = Eigen::Vector3d::UnitZ();
  PlantSpec b = a;
  b.base = Eigen::Vector3d(1.5 * a.width, 0, 0);  // close enough to touch when bent
  BeamParameters parameters;
  parameters.gravity = Eigen::Vector3d(0, 0, -9.81);
  return PlantField({a, b}, parameters);
}

// Window w's flow: a gust that bends the plants into each other and back.
std::vector<Eigen::Vector3d> flow(const PlantField& field, int w) {
  const double u = 0.6 * std::sin(0.3 * w);
  return std::vector<Eigen::Vector3d>(field.node_count(), Eigen::Vector3d(u, 0.1 * u, 0));
}

void run_windows(PlantField& field, int from, int to) {
  std::vector<double> wet(field.node_count());
  for (int w = from; w < to; ++w) {
    for (int k = 0; k < field.node_count(); ++k) wet[k] = k % 5 == 0 ? 0.5 : 1.0;
    field.set_water_fraction(wet);
    std::vector<Eigen::Vector3d> push(field.node_count(), Eigen::Vector3d(0.001 * (w % 3), 0, 0));
    field.set_external_forces(push);
    field.advance(2e-3, flow(field, w), flow(field, w + 1));
  }
}

TEST(PlantCheckpoint, LoadedFieldContinuesBitForBit) {
  PlantField straight = make_field();
  run_windows(straight, 0, 40);
  checkpoint::Writer out("vegetation_beam");
  save_checkpoint(straight, out);
  const auto path = std::filesystem::temp_directory_path() / "cosim_plant_checkpoint.ckpt";
  out.save(path);

  PlantField restored = make_field();
  load_checkpoint(restored, checkpoint::Reader(path, "vegetation_beam"));
  EXPECT_EQ(restored.time(), straight.time());
  EXPECT_TRUE(same_bits(restored.positions(), straight.positions()));
  run_windows(straight, 40, 80);
  run_windows(restored, 40, 80);
  EXPECT_TRUE(same_bits(restored.positions(), straight.positions()));
  EXPECT_TRUE(same_bits(restored.velocities(), straight.velocities()));
  EXPECT_TRUE(same_bits(restored.window_mean_drag(), straight.window_mean_drag()));
  // Not trivially equal: the plants moved after the checkpoint.
  PlantField fresh = make_field();
  EXPECT_FALSE(same_bits(fresh.positions(), straight.positions()));
}

TEST(PlantCheckpoint, AnotherSceneIsRefusedByName) {
  PlantField field = make_field();
  checkpoint::Writer out("vegetation_beam");
  save_checkpoint(field, out);
  const auto path = std::filesystem::temp_directory_path() / "cosim_plant_checkpoint_other.ckpt";
  out.save(path);
  PlantSpec single;
  single.length = 0.1;
  single.width = 0.01;
  single.thickness = 0.002;
  single.youngs_modulus = 1e8;
  PlantField other({single}, BeamParameters{});
  try {
    load_checkpoint(other, checkpoint::Reader(path));
    FAIL() << "a checkpoint of two plants was loaded into one";
  } catch (const checkpoint::Error& error) {
    EXPECT_NE(std::string(error.what()).find("plants.node_count"), std::string::npos)
        << error.what();
  }
}

}  // namespace
}  // namespace cosim::vegetation
