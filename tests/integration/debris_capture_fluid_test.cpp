// The CI-sized debris_capture_fluid: a 3D MPS reservoir released down a 15 degree flume carries
// a gated debris packing to a grid dam, both ways coupled. Checked: the run is stable, every
// fluid particle is in the flume or counted through its outlet, fluid and DEM walls coincide, no
// element is lost, the front reaches the dam, the fluid's drag moves the debris downstream and
// the fluid takes back what the debris took, and P_V is reported.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <string>

#include "command.hpp"
#include "cosim/output/point_series.hpp"

namespace cosim::testing {
namespace {

const nlohmann::json& participant(const nlohmann::json& summary, const std::string& name) {
  for (const auto& entry : summary["participants"]) {
    if (entry["name"] == name) return entry;
  }
  throw std::runtime_error("no participant " + name);
}

// scenarios/debris_capture_fluid reduced: a 1.2 m reach 0.16 m wide, l0 = 2 cm (about 500
// water particles, 10 000 in all), 100 boulders and 6 logs, 0.8 s after the gate opens. The walls
// are 0.3 m high: the surge that runs up the end wall (u^2 / 2g ~ 0.3 m) stays in the flume.
constexpr double kLength = 1.2, kWidth = 0.16, kWallHeight = 0.3, kDam = 0.8;
// The DEM's section of both CI scenes: the flume, its roughness and dam, 100 boulders and 6 logs
// behind the gate.
const std::string kDebris = fmt::format(R"(  debris_dem:
    substep: 1.0e-5
    flume: {{length: {0}, width: {1}, wall_height: {2}}}
    bed_roughness: {{x0: 0.3, x1: {0}, d_min: 0.007, d_max: 0.02, seed: 3}}
    dam: {{x: {3}, column_diameter: 0.018, horizontal_gap: 0.05, vertical_gap: 0.03,
           height: 0.14}}
    front_gauge_x: 0.6
    packing:
      box_min: [0.05, 0, 0]
      box_max: [0.3, {1}, 0.12]
      spheres:
        - {{diameter: 0.020, count: 40}}
        - {{diameter: 0.015, count: 60}}
      log_count: 6
      seed: 9
    gate: {{x: 0.3, settle_time: 0.3}}
)",
                                        kLength, kWidth, kWallHeight, kDam);
// The top of both CI scenes: the run, the 15 degree world, the coupling and the 3D fluid's own
// keys at l0 = 2 cm (its scene follows).
std::string scene_head(const std::string& name, double duration) {
  return fmt::format(R"(name: {}
duration: {}
output_interval: 0.1
world:
  slope_degrees: 15
coupling:
  scheme: serial-explicit
  window: 2.0e-3
  adaptive_window: true
participants:
  fluid_mps:
    dimension: 3
    particle_spacing: 0.02
    kinematic_viscosity: 1.0e-6
    radius_laplacian_over_l0: 3.1
    max_dt: 2.0e-3        # at l0 = 2 cm the Courant limit (0.2 l0 / u) allows it below 2 m/s
    sample_radius: 0.04
)",
                     name, duration);
}

const std::string kScene = scene_head("debris_capture_fluid_ci", 0.8) +
                           fmt::format(R"(    scene:
      kind: flume
      length: {0}
      width: {1}
      wall_height: {2}
      dummy_layers: 1
      water: {{x_max: 0.3, depth: 0.08}}
      outlet_x: 1.15
)",
                                       kLength, kWidth, kWallHeight) +
                           kDebris;

TEST(DebrisCaptureFluid, ASurgeCarriesTheDebrisToTheDamWithNothingLost) {
  const auto folder = fresh_folder("debris-capture-fluid");
  std::ofstream(folder / "scenario.yaml") << kScene;
  const auto result =
      run_cosim(fmt::format("run {} --runs-dir {} --quiet", folder.string(), folder.string()), 85);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const auto run = run_folder_of(result);
  const auto summary = read_summary(run);
  const auto& debris = participant(summary, "debris_dem")["report"];
  const auto& fluid = participant(summary, "fluid_mps")["report"]["info"];

  // No fluid particle lost: the fluid particles at the end and those that left through the
  // outlet are those of the start, and all inside the flume (walls at 0 and length, 0 and
  // width).
  // A particle pressed against a wall may sit a little inside it (MPS walls hold the fluid by
  // pressure, not as a hard face), never beyond the first wall layer's centres l0 / 2 behind.
  const double tolerance = 0.5 * 0.02;
  const auto h5 = run / "fluid_mps" / "particles.h5";
  const auto first = output::read_point_frame(h5, 0);
  const auto last = output::read_point_frame(h5, -1);
  auto fluid_count = [](const output::PointFrame& frame) {
    int n = 0;
    for (const int kind : frame.labels.at("kind")) n += kind == 0;
    return n;
  };
  ASSERT_GT(fluid_count(first), 300);
  EXPECT_EQ(fluid_count(last) + fluid["outlet_particles"].get<int>(), fluid_count(first));
  const auto& kinds = last.labels.at("kind");
  for (std::size_t i = 0; i < kinds.size(); ++i) {
    if (kinds[i] != 0) continue;
    const Eigen::Vector3d& x = last.positions[i];
    ASSERT_TRUE(x.x() > -tolerance && x.x() < kLength + tolerance && x.y() > -tolerance &&
                x.y() < kWidth + tolerance && x.z() > -tolerance)
        << "fluid particle " << i << " at " << x.transpose();
  }
  // Fluid and DEM see the same flume: the DEM's wall triangles (bed, sides, upstream wall) span
  // [0, L] x [0, W] x [0, H], no fluid wall particle stands inside that space, and each face is
  // lined with wall particles a whole face wide, l0 / 2 behind it (the lattice cells behind the
  // face); the fluid's lattice also ends in a wall at x = L, behind its outlet.
  const auto triangles = output::read_point_frame(run / "debris_dem" / "structure.h5", 1);
  Eigen::AlignedBox3d dem_flume;
  for (const auto& v : triangles.positions) dem_flume.extend(v);
  EXPECT_LT((dem_flume.min() - Eigen::Vector3d::Zero()).norm(), 1e-12);
  EXPECT_LT((dem_flume.max() - Eigen::Vector3d(kLength, kWidth, kWallHeight)).norm(), 1e-12);
  const double l0 = 0.02;
  int bed = 0, side = 0, upstream = 0, downstream = 0;
  for (std::size_t i = 0; i < first.positions.size(); ++i) {
    if (first.labels.at("kind")[i] != 1) continue;  // wall particles
    const Eigen::Vector3d& x = first.positions[i];
    ASSERT_FALSE(dem_flume.contains(x))
        << "wall particle inside the DEM's flume at " << x.transpose();
    const bool along = (x.x() > 0.0) && (x.x() < kLength);
    const bool across = (x.y() > 0.0) && (x.y() < kWidth);
    const bool up = (x.z() > 0.0) && (x.z() < kWallHeight);
    bed += along && across && std::abs(x.z() + 0.5 * l0) < 1e-9;
    side += along && up && std::abs(x.y() + 0.5 * l0) < 1e-9;
    upstream += across && up && std::abs(x.x() + 0.5 * l0) < 1e-9;
    downstream += across && up && std::abs(x.x() - kLength - 0.5 * l0) < 1e-9;
  }
  const auto cells = [&](double a, double b) { return std::lround(a / l0) * std::lround(b / l0); };
  EXPECT_EQ(bed, cells(kLength, kWidth));
  EXPECT_EQ(side, cells(kLength, kWallHeight));
  EXPECT_EQ(upstream, cells(kWidth, kWallHeight));
  EXPECT_EQ(downstream, cells(kWidth, kWallHeight));

  // No element lost; those still on the flume are between its walls.
  const auto elements = output::read_point_frame(run / "debris_dem" / "debris.h5", -1);
  EXPECT_EQ(elements.positions.size(), 106u);
  for (const auto& x : elements.positions) {
    const bool on_flume = x.x() < kLength;
    EXPECT_TRUE(!on_flume || (x.x() > 0.0 && x.y() > 0.0 && x.y() < kWidth)) << x.transpose();
  }

  // The debris reached the dam: its front passed the gauge 0.2 m upstream of it, and part of
  // it is within 0.2 m of the dam or beyond.
  const auto& metrics = debris["metrics"];
  ASSERT_FALSE(metrics["debris_front_time"]["value"].is_null()) << metrics.dump();
  EXPECT_GT(metrics["debris_front_time"]["value"].get<double>(), 0.0);
  EXPECT_GT(metrics["debris_front_length"]["value"].get<double>(), 0.0);
  EXPECT_GT(metrics["debris_arrived_at_dam"]["value"].get<double>(), 0.0);
  const double p_v = metrics["capture_rate_P_V"]["value"].get<double>();
  EXPECT_GE(p_v, 0.0);
  EXPECT_LE(p_v, 1.0);

  // The fluid's forces moved the debris downstream, and the fluid took back, one window later,
  // everything the debris took from it (drag; 3D: nothing out of plane).
  const Eigen::Vector3d pushed = vector_of(debris["info"]["fluid_impulse"]);
  const Eigen::Vector3d took = vector_of(debris["info"]["interaction_impulse"]);
  const Eigen::Vector3d last_window = vector_of(debris["info"]["last_window_interaction_impulse"]);
  EXPECT_GT(took.x(), 1e-4) << "the surge drags the debris along the flume: " << took.transpose();
  EXPECT_GT(pushed.x(), 0.0);
  const auto [booked, received, undelivered, out_of_plane] = flow_impulses(fluid);
  EXPECT_LT((booked + (took - last_window)).norm(), 1e-9 * took.norm())
      << booked.transpose() << " vs " << (took - last_window).transpose();
  EXPECT_EQ(out_of_plane.norm(), 0.0);
  EXPECT_LT((received + undelivered - booked).norm(), 1e-9 * booked.norm());
  // The fluid's momentum budget, the debris' reaction included, closes.
  EXPECT_LT(fluid["momentum_budget_residual"].get<double>(), 1e-12);
}

// The same reach fed by a sustained inflow instead of a reservoir: the 3D open_channel (its bed
// and side walls where the DEM's flume triangles are) with seed 001's soluble moving wall across
// the width upstream of the DEM's upstream wall, q = 0.03 m^2/s per width for the whole run (a
// deeper flow than seed 004's 4.3 l/s over 0.3 m, so that l0 = 2 cm resolves it), and a free
// overfall at the flume's end, where the DEM's debris leaves too.
const std::string kInflowScene = scene_head("debris_capture_inflow_ci", 1.0) +
                                 fmt::format(R"(    scene:
      kind: open_channel
      length: {0}
      tank_width: {1}
      tank_height: 0.12
      dummy_layers: 1
      initial_depth: 0.0
      block_height: 0.1
      pool_particles: 6000
      inflow: {{control: discharge, discharge: 0.03, ramp_time: 0.1}}
)",
                                             kLength, kWidth) +
                                 kDebris;

TEST(DebrisCaptureFluid, ASustainedInflowCarriesTheDebrisToTheDam) {
  const auto folder = fresh_folder("debris-capture-inflow");
  std::ofstream(folder / "scenario.yaml") << kInflowScene;
  const auto result =
      run_cosim(fmt::format("run {} --runs-dir {} --quiet", folder.string(), folder.string()), 150);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const auto run = run_folder_of(result);
  const auto summary = read_summary(run);
  const auto& debris = participant(summary, "debris_dem")["report"];
  const auto& fluid = participant(summary, "fluid_mps")["report"]["info"];
  // The inflow ran the whole time: q times the width over the run, less the soft start's half
  // (0.1 s), within the last column's volume; the water reached the overfall and left.
  const double expected = 0.03 * kWidth * (1.0 - 0.05);
  EXPECT_NEAR(fluid["inflow_volume"].get<double>(), expected, 0.05 * expected) << fluid.dump(1);
  EXPECT_GT(fluid["recycled_particles"].get<int>(), 100) << fluid.dump(1);
  // Every fluid particle between the fluid's walls, or past the overfall on its way out.
  const auto last = output::read_point_frame(run / "fluid_mps" / "particles.h5", -1);
  const double tolerance = 0.5 * 0.02;
  const auto& kinds = last.labels.at("kind");
  for (std::size_t i = 0; i < kinds.size(); ++i) {
    if (kinds[i] != 0) continue;
    const Eigen::Vector3d& x = last.positions[i];
    if (x.x() > kLength) continue;
    ASSERT_TRUE(x.x() > -tolerance && x.y() > -tolerance && x.y() < kWidth + tolerance &&
                x.z() > -tolerance)
        << "fluid particle " << i << " at " << x.transpose();
  }
  // No element lost; the flow carried the debris past the gauge to the dam.
  const auto elements = output::read_point_frame(run / "debris_dem" / "debris.h5", -1);
  EXPECT_EQ(elements.positions.size(), 106u);
  const auto& metrics = debris["metrics"];
  ASSERT_FALSE(metrics["debris_front_time"]["value"].is_null()) << metrics.dump();
  EXPECT_GT(metrics["debris_arrived_at_dam"]["value"].get<double>(), 0.0);
  const double p_v = metrics["capture_rate_P_V"]["value"].get<double>();
  EXPECT_GE(p_v, 0.0);
  EXPECT_LE(p_v, 1.0);
  // The fluid took back, one window later, everything the debris took from it.
  const Eigen::Vector3d took = vector_of(debris["info"]["interaction_impulse"]);
  const Eigen::Vector3d last_window = vector_of(debris["info"]["last_window_interaction_impulse"]);
  EXPECT_GT(took.x(), 1e-4) << took.transpose();
  const auto [booked, received, undelivered, out_of_plane] = flow_impulses(fluid);
  EXPECT_LT((booked + (took - last_window)).norm(), 1e-9 * took.norm())
      << booked.transpose() << " vs " << (took - last_window).transpose();
  EXPECT_LT((received + undelivered - booked).norm(), 1e-9 * booked.norm());
}

// `cosim validate` refuses what the fluid process would refuse with file, line and key: the
// 3D-only flume in a 2D fluid (no 2D builder), and a flume that is not whole lattice cells long
// (its end wall would not stand where the DEM's does).
TEST(DebrisCaptureFluid, ValidateRefusesAFlumeTheFluidCannotBuild) {
  struct Case {
    std::string from, to, key, problem;
  };
  for (const Case& c :
       {Case{"    dimension: 3\n", "    dimension: 2\n", "kind", "'flume' is a 3D scene"},
        Case{"length: 1.2\n", "length: 1.21\n", "length",
             "is not a whole number of particle_spacing"}}) {
    const auto folder = fresh_folder("debris-capture-fluid-refused");
    std::string yaml = kScene;
    yaml.replace(yaml.find(c.from), c.from.size(), c.to);
    std::ofstream(folder / "scenario.yaml") << yaml;
    const auto result = run_cosim(fmt::format("validate {}", folder.string()), 60);
    EXPECT_NE(result.exit_code, 0) << result.output;
    const auto before = yaml.substr(0, yaml.find(c.key == "kind" ? "kind: flume" : c.to));
    const auto line = 1 + std::count(before.begin(), before.end(), '\n');
    EXPECT_NE(result.output.find(fmt::format(
                  "scenario.yaml:{}: key 'participants.fluid_mps.scene.{}'", line, c.key)),
              std::string::npos)
        << result.output;
    EXPECT_NE(result.output.find(c.problem), std::string::npos) << result.output;
  }
}

}  // namespace
}  // namespace cosim::testing
