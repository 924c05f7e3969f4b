// The 3D fluid scenes through cosim at CI size: scenarios/dam_break_3d at a/l0 = 5 (6 000
// particles) against Martin & Moyce, scenarios/still_water_3d at l0 = 1.25 cm against rho g depth
// (about 60 s), and the 3D output: HDF5 frames with every field and positions spread over x, y and
// z, and the XDMF index next to them; a restart from a 3D frame; a box obstacle stays solid.
// 2D-only scene kinds are refused in 3D by `cosim validate`.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "command.hpp"
#include "cosim/output/point_series.hpp"

namespace cosim::testing {
namespace {

TEST(Fluid3d, DamBreakAgainstMartinMoyceWithThreeDimensionalOutput) {
  const auto runs = fresh_folder("fluid-3d-dam-break");
  const auto result = run_cosim(
      fmt::format(
          "run {} --runs-dir {} --quiet --set participants.fluid_mps.particle_spacing=0.01143",
          scenario("dam_break_3d"), runs.string()),
      120);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const auto folder = run_folder_of(result);
  const auto summary = read_summary(folder);
  const auto& metrics = metrics_of(summary);
  ASSERT_TRUE(metrics.contains("surge_front_error")) << metrics.dump(1);
  ASSERT_TRUE(metrics.contains("residual_height_error")) << metrics.dump(1);
  // Measured at this resolution: front 6.3 %, residual height 5.8 % (docs/validation.md).
  EXPECT_LT(metrics["surge_front_error"]["relative_error"].get<double>(), 0.15);
  EXPECT_LT(metrics["residual_height_error"]["relative_error"].get<double>(), 0.15);
  const auto& info = summary["participants"][0]["report"]["info"];
  EXPECT_LT(info["momentum_budget_residual"].get<double>(), 1e-10);
  // Closed tank: no momentum across the width (the walls are symmetric), at round-off.
  EXPECT_LT(std::abs(info["fluid_momentum_change"][1].get<double>()), 1e-10);

  const auto h5 = folder / "fluid_mps" / "particles.h5";
  ASSERT_TRUE(std::filesystem::exists(folder / "fluid_mps" / "particles.xmf"));
  ASSERT_EQ(output::count_point_frames(h5), 21);  // t = 0, 0.01, ..., 0.2
  const auto first = output::read_point_frame(h5, 0);
  const auto last = output::read_point_frame(h5, -1);
  EXPECT_EQ(last.positions.size(), first.positions.size());
  for (const char* name : {"pressure", "number_density"}) {
    ASSERT_TRUE(last.scalars.count(name)) << name;
    EXPECT_EQ(last.scalars.at(name).size(), last.positions.size());
  }
  ASSERT_TRUE(last.vectors.count("velocity"));
  ASSERT_TRUE(last.labels.count("kind"));
  // World frame, z up: the water spans the tank's width (y in [0, a]) and has fallen and spread
  // along x; fluid moves in x and z, walls do not move.
  const double a = 0.05715;
  double y_min = 1, y_max = -1, x_max = 0, z_max = 0, u_max = 0;
  for (std::size_t i = 0; i < last.positions.size(); ++i) {
    const auto& x = last.positions[i];
    if (last.labels.at("kind")[i] != 0) {
      EXPECT_EQ(x, first.positions[i]);
      continue;
    }
    y_min = std::min(y_min, x.y());
    y_max = std::max(y_max, x.y());
    x_max = std::max(x_max, x.x());
    z_max = std::max(z_max, x.z());
    u_max = std::max(u_max, last.vectors.at("velocity")[i].norm());
  }
  EXPECT_GT(y_min, 0.0);
  EXPECT_LT(y_max, a);
  EXPECT_GT(y_max - y_min, 0.5 * a);
  EXPECT_GT(x_max, 3.0 * a);
  EXPECT_LT(z_max, 2.0 * a);
  EXPECT_GT(u_max, 0.5);
}

template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

// A 3D frame holds all a restart needs (the world frame is the solver's in 3D): restarted from
// frame 2 the run ends on the same bits as the straight one.
TEST(Fluid3d, RestartFromAnOutputFrameMatchesTheStraightRun) {
  const auto runs = fresh_folder("fluid-3d-restart");
  const std::string coarse =
      "--set participants.fluid_mps.particle_spacing=0.01143 --set coupling.adaptive_window=false "
      "--set coupling.window=5.0e-4";
  const auto straight = run_cosim(fmt::format("run {} --runs-dir {} --quiet {} --set duration=0.04",
                                              scenario("dam_break_3d"), runs.string(), coarse));
  ASSERT_EQ(straight.exit_code, 0) << straight.output;
  const auto straight_output = run_folder_of(straight) / "fluid_mps" / "particles.h5";
  ASSERT_EQ(output::count_point_frames(straight_output), 5);  // t = 0, 0.01, ..., 0.04
  const auto restarted = run_cosim(
      fmt::format("run {} --runs-dir {} --quiet {} --set duration=0.02 "
                  "--set participants.fluid_mps.restart.file={} "
                  "--set participants.fluid_mps.restart.frame=2",
                  scenario("dam_break_3d"), runs.string(), coarse, straight_output.string()));
  ASSERT_EQ(restarted.exit_code, 0) << restarted.output;
  const auto expected = output::read_point_frame(straight_output, -1);
  const auto actual =
      output::read_point_frame(run_folder_of(restarted) / "fluid_mps" / "particles.h5", -1);
  EXPECT_EQ(expected.time, actual.time);
  EXPECT_TRUE(same_bits(expected.positions, actual.positions));
  EXPECT_TRUE(same_bits(expected.vectors.at("velocity"), actual.vectors.at("velocity")));
  EXPECT_TRUE(same_bits(expected.scalars.at("pressure"), actual.scalars.at("pressure")));
}

TEST(Fluid3d, BoxObstacleStaysSolid) {
  const auto runs = fresh_folder("fluid-3d-box");
  const auto result = run_cosim(fmt::format("run {} --runs-dir {} --quiet",
                                            test_scene("box_dam_break_3d").string(), runs.string()),
                                120);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const auto h5 = run_folder_of(result) / "fluid_mps" / "particles.h5";
  const auto first = output::read_point_frame(h5, 0);
  const auto last = output::read_point_frame(h5, -1);
  // The box [0.12, 0.16] x [0.03, 0.07] x [0, 0.03] m: 4 x 4 x 3 cells, all wall particles (each
  // lies within 2 cells of an open face), and no water centre more than l0 / 2 inside it.
  const double l0 = 0.01;
  const Eigen::Vector3d low(0.12, 0.03, 0.0), high(0.16, 0.07, 0.03);
  const Eigen::Vector3d inner_low = low + 0.5 * l0 * Eigen::Vector3d(1, 1, 0);
  const Eigen::Vector3d inner_high = high - 0.5 * l0 * Eigen::Vector3d::Ones();
  int box_walls = 0;
  double reach = 0;
  for (std::size_t i = 0; i < last.positions.size(); ++i) {
    const auto& x = last.positions[i];
    const int kind = last.labels.at("kind")[i];
    const bool inside = (x.array() > low.array()).all() && (x.array() < high.array()).all();
    if (kind == 1 && inside) ++box_walls;
    if (kind != 0) continue;
    reach = std::max(reach, x.x());
    const bool deep =
        (x.array() > inner_low.array()).all() && (x.array() < inner_high.array()).all();
    EXPECT_FALSE(deep) << "water inside the box at " << x.transpose();
  }
  EXPECT_EQ(box_walls, 4 * 4 * 3);
  EXPECT_EQ(first.positions.size(), last.positions.size());
  EXPECT_GT(reach, high.x());  // the water went past the box
}

TEST(Fluid3d, StillWaterHydrostaticPressure) {
  const auto runs = fresh_folder("fluid-3d-still-water");
  // The bundle on its fcc start at l0 = 1.25 cm (5 750 particles, 2 000 windows): on a loaded
  // machine one fluid answer was once silent for more than the default 5 s (window 1183), so the
  // hang detector waits 30 s here.
  const auto result = run_cosim(
      fmt::format(
          "run {} --runs-dir {} --quiet --set participants.fluid_mps.particle_spacing=0.0125 "
          "--set coupling.timeout=30",
          scenario("still_water_3d"), runs.string()),
      240);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const auto summary = read_summary(run_folder_of(result));
  const auto& metrics = metrics_of(summary);
  // Measured at l0 = 1.25 cm: +3.23 / +1.64 / +1.04 % at depths 5 / 10 / 15 cm (within 2 % from
  // l0 = 6.25 mm on; docs/validation.md, still_water_3d). The error is a shift of the free
  // surface's p = 0 condition (about 0.15 l0 above the water it holds), so it is positive and
  // falls with depth as 1 / depth; the simple cubic start read -2.0 / -2.8 / -1.9 % here and
  // -5.0 % at 5 cm at l0 = 1 cm, as it sank.
  std::vector<double> errors;
  for (const double depth : {0.05, 0.1, 0.15}) {
    const std::string name = fmt::format("pressure_at_depth_{:.4g}m", depth);
    ASSERT_TRUE(metrics.contains(name)) << metrics.dump(1);
    const auto& metric = metrics[name];
    const double error = metric["value"].get<double>() / metric["reference"].get<double>() - 1.0;
    EXPECT_GT(error, 0.0) << name << ": " << metric.dump();
    EXPECT_LT(error, 0.045) << name << ": " << metric.dump();
    errors.push_back(error);
  }
  EXPECT_GT(errors[0], errors[1]);
  EXPECT_GT(errors[1], errors[2]);
  // The fcc packing keeps its volume and its order: the level 0.27 mm (0.02 l0) below the start
  // over 1-2 s, the water at 1.2e-6 J/kg (the cubic start: 1.67 mm, 7.7e-5 J/kg).
  const auto& info = summary["participants"][0]["report"]["info"];
  const double l0 = 0.0125;
  ASSERT_TRUE(info.contains("water_level_drop")) << info.dump(1);
  EXPECT_GT(info["water_level_drop"].get<double>(), 0.0);
  EXPECT_LT(info["water_level_drop"].get<double>(), 0.05 * l0);
  EXPECT_LT(info["mean_kinetic_energy"].get<double>(), 1e-5);
}

TEST(Fluid3d, ValidateRefusesSceneKindsWithoutA3dBuilder) {
  const auto result = run_cosim(fmt::format("validate {} --set participants.fluid_mps.dimension=3",
                                            scenario("fishway_overflow")));
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(result.output.find("scenario.yaml:"), std::string::npos) << result.output;
  EXPECT_NE(result.output.find("key 'participants.fluid_mps.scene.kind'"), std::string::npos)
      << result.output;
  EXPECT_NE(result.output.find("has no 3D scene"), std::string::npos) << result.output;
  // A 3D tank needs its width across.
  const auto missing = run_cosim(fmt::format("validate {} --set participants.fluid_mps.dimension=3",
                                             scenario("dam_break_2d")));
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.output.find("scene.tank_width"), std::string::npos) << missing.output;
  // An obstacle box must have a positive size.
  const auto flat = run_cosim(
      fmt::format("validate {} --set participants.fluid_mps.scene.obstacles.0.max=[0.1,0.07,0.03]",
                  test_scene("box_dam_break_3d").string()));
  EXPECT_NE(flat.exit_code, 0);
  EXPECT_NE(flat.output.find("scene.obstacles[0].max"), std::string::npos) << flat.output;
  EXPECT_NE(flat.output.find("must exceed min"), std::string::npos) << flat.output;
}

// fill_lattice (MpsParameters): a 3D scene takes fcc; an unknown lattice, and fcc in 2D, are
// refused at the key's line.
TEST(Fluid3d, ValidateChecksTheFillLattice) {
  const auto fcc = run_cosim(fmt::format(
      "validate {} --set participants.fluid_mps.fill_lattice=fcc", scenario("still_water_3d")));
  EXPECT_EQ(fcc.exit_code, 0) << fcc.output;
  const auto unknown = run_cosim(fmt::format(
      "validate {} --set participants.fluid_mps.fill_lattice=hcp", scenario("still_water_3d")));
  EXPECT_NE(unknown.exit_code, 0);
  EXPECT_NE(unknown.output.find("key 'participants.fluid_mps.fill_lattice'"), std::string::npos)
      << unknown.output;
  EXPECT_NE(unknown.output.find("is not one of: cubic, fcc"), std::string::npos) << unknown.output;
  const auto flat = run_cosim(fmt::format(
      "validate {} --set participants.fluid_mps.fill_lattice=fcc", scenario("still_water")));
  EXPECT_NE(flat.exit_code, 0);
  EXPECT_NE(flat.output.find("scenario.yaml:"), std::string::npos) << flat.output;
  EXPECT_NE(flat.output.find("fcc is a 3D lattice"), std::string::npos) << flat.output;
}

}  // namespace
}  // namespace cosim::testing
