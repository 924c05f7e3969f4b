// A DEM world saved mid-run (a pile settling in a box, spheres and logs in contact) and loaded
// into a world built from the same scene continues with the same bits as the one that ran on.
#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "cosim/debris_dem/checkpoint.hpp"
#include "cosim/debris_dem/scenes.hpp"

namespace cosim::dem {
namespace {

void build(DemWorld& world) {
  Material m;
  Material wood = m;
  wood.density = 800;
  FlumeSpec box;
  box.length = 0.2;
  box.width = 0.2;
  box.wall_height = 0.3;
  add_flume(world, box, m);
  world.add_triangle({0.2, 0, 0}, {0.2, 0.2, 0}, {0.2, 0.2, 0.3}, m);
  world.add_triangle({0.2, 0, 0}, {0.2, 0.2, 0.3}, {0.2, 0, 0.3}, m);
  PackingSpec spec;
  spec.box_min = {0.0, 0.0, 0.0};
  spec.box_max = {0.2, 0.2, 0.25};
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> d(0.01, 0.02);
  for (int i = 0; i < 40; ++i) spec.sphere_diameters.push_back(d(rng));
  spec.log_count = 2;
  spec.seed = 3;
  random_packing(world, spec, m, wood);
}

std::vector<double> state(const DemWorld& world) {
  std::vector<double> values;
  for (int i = 0; i < world.element_count(); ++i) {
    for (const auto& v : {world.position(i), world.velocity(i), world.angular_velocity(i)})
      values.insert(values.end(), v.data(), v.data() + 3);
    const auto q = world.orientation(i).coeffs();
    values.insert(values.end(), q.data(), q.data() + 4);
  }
  return values;
}

bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

// Flow through the pile, changing from window to window.
FluidAtElements fluid(const DemWorld& world, int w) {
  FluidAtElements f;
  const std::size_t n = world.moving_elements().size();
  f.velocity.assign(n, Eigen::Vector3d(0.2 * std::sin(0.1 * w), 0.0, 0.05));
  f.water_fraction.assign(n, 0.7);
  return f;
}

TEST(DemCheckpoint, LoadedWorldContinuesBitForBit) {
  DemWorld straight;
  build(straight);
  for (int w = 0; w < 250; ++w) straight.advance(1e-3, fluid(straight, w));
  ASSERT_GT(straight.contact_count(), 0);
  checkpoint::Writer out("debris_dem");
  save_checkpoint(straight, out);
  const auto path = std::filesystem::temp_directory_path() / "cosim_dem_checkpoint.ckpt";
  out.save(path);

  DemWorld restored;
  build(restored);
  load_checkpoint(restored, checkpoint::Reader(path, "debris_dem"));
  EXPECT_TRUE(same_bits(state(restored), state(straight)));
  for (int w = 250; w < 350; ++w) {
    straight.advance(1e-3, fluid(straight, w));
    restored.advance(1e-3, fluid(restored, w));
  }
  EXPECT_TRUE(same_bits(state(restored), state(straight)));
  EXPECT_EQ(restored.step_count(), straight.step_count());
  EXPECT_EQ(restored.list_rebuilds(), straight.list_rebuilds());
  DemWorld fresh;
  build(fresh);
  EXPECT_FALSE(same_bits(state(fresh), state(straight)));
}

TEST(DemCheckpoint, AnotherSceneIsRefusedByName) {
  DemWorld world;
  build(world);
  checkpoint::Writer out("debris_dem");
  save_checkpoint(world, out);
  const auto path = std::filesystem::temp_directory_path() / "cosim_dem_checkpoint_other.ckpt";
  out.save(path);
  DemWorld other;
  other.add_sphere({0, 0, 0}, 0.01, Material{});
  try {
    load_checkpoint(other, checkpoint::Reader(path));
    FAIL() << "a checkpoint of another scene was loaded";
  } catch (const checkpoint::Error& error) {
    EXPECT_NE(std::string(error.what()).find("dem.elements"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace cosim::dem
