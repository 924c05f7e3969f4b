// Scenario keys of the standard beam checks, from the vegetation_beam section through
// parse_config and prepare_start, against references/cantilever.md: point and tip loads with
// static_solve (small-deflection statics), plucks (free vibration at the natural frequencies),
// modal output; and the Newton keys.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "beam_checks.hpp"
#include "beam_test_helpers.hpp"
#include "cosim/scenario/scene.hpp"
#include "vegetation_config.hpp"

namespace cosim::vegetation {
namespace {

using testing::cantilever_frequency;

// A vegetation_beam section in vacuum without gravity (fluid_density 0, world gravity zero),
// undamped, no contact: the textbook cantilever of beam_test_helpers.hpp (L = 1 m, 1 cm square,
// E = 1 GPa, EI = 0.8333 N m^2, 1000 kg/m^3) standing along z with `links` links. `extra` is
// appended to the plant entry, `section_extra` to the section.
std::string vacuum_section(int links, const std::string& extra,
                           const std::string& section_extra = "") {
  return "fluid_density: 0\n"
         "axial_damping_ratio: 0\n"
         "bending_damping_ratio: 0\n"
         "contact: false\n" +
         section_extra +
         "plants:\n"
         "  - base: [0, 0, 0]\n"
         "    direction: [0, 0, 1]\n"
         "    length: 1.0\n"
         "    links: " +
         std::to_string(links) +
         "\n"
         "    width: 0.01\n"
         "    thickness: 0.01\n"
         "    youngs_modulus: 1.0e9\n"
         "    density: 1000\n" +
         extra;
}

VegetationConfig parse(const std::string& yaml) {
  scenario::Scene scene;
  scene.output_interval = 0.01;
  scene.world.gravity = Eigen::Vector3d::Zero();
  YAML::Node resolved(YAML::NodeType::Map);
  scenario::Section section = scenario::Section::root(YAML::Load(yaml), "checks.yaml", resolved);
  VegetationConfig config = parse_config(section, scene);
  section.finish();
  return config;
}

std::string parse_error(const std::string& yaml) {
  try {
    parse(yaml);
  } catch (const scenario::ScenarioError& error) {
    return error.what();
  }
  return "no error";
}

constexpr double kBending = 1e9 * 1e-8 / 12;    // E b t^3 / 12, N m^2
constexpr double kMassPerLength = 1000 * 1e-4;  // kg/m

// Tip load P with P L^3 / (3 EI) = 1e-4 L: tip deflection and rotation (cantilever.md).
TEST(BeamChecks, TipLoadWithStaticSolveGivesTheCantileverDeflectionAndRotation) {
  const double load = 3 * kBending * 1e-4;
  const VegetationConfig config = parse(vacuum_section(
      32, "    point_loads:\n      - {at: 1.0, force: [" + std::to_string(load) + ", 0, 0]}\n",
      "static_solve: true\n"));
  ASSERT_EQ(config.checks.point_loads.size(), 1u);
  EXPECT_EQ(config.checks.point_loads[0].node, 32);
  PlantField field(config.plants, config.parameters);
  const StartReport start = prepare_start(field, config.checks);
  EXPECT_GT(start.static_iterations, 0);
  const double deflection = field.tip_displacement(0).x();
  const auto [first, last] = field.node_range(0);
  const Eigen::Vector3d end_link = field.positions()[last - 1] - field.positions()[last - 2];
  const double rotation = std::atan2(end_link.x(), end_link.z());
  const double reference_deflection = load / (3 * kBending),
               reference_rotation = load / (2 * kBending);
  std::printf(
      "tip load: deflection %.6e m vs %.6e m (%+.3f %%), rotation %.6e vs %.6e (%+.3f %%)\n",
      deflection, reference_deflection, 100 * (deflection / reference_deflection - 1), rotation,
      reference_rotation, 100 * (rotation / reference_rotation - 1));
  EXPECT_NEAR(deflection / reference_deflection, 1.0, 0.005);
  // The last link's slope is that of its midpoint, L - l0/2: theta(s) = P s (2L - s) / (2 EI).
  const double s = 1.0 - 0.5 / 32;
  EXPECT_NEAR(rotation / (load * s * (2 - s) / (2 * kBending)), 1.0, 0.005);
  EXPECT_NEAR(rotation / reference_rotation, 1.0, 0.01);
  (void)first;
}

// A point load at mid-length: by Maxwell-Betti the tip deflection equals the deflection at L/2
// under the same load at the tip, P a^2 (3L - a) / (6 EI) with a = L/2 (the tip-load elastic
// curve of cantilever.md's case: w(s) = P s^2 (3L - s) / (6 EI)), i.e. 5 P L^3 / (48 EI).
TEST(BeamChecks, MidLengthPointLoadGivesTheReciprocalDeflection) {
  const double load = 1e-4 * kBending;
  const VegetationConfig config = parse(vacuum_section(
      32, "    point_loads:\n      - {at: 0.5, force: [0, " + std::to_string(load) + ", 0]}\n",
      "static_solve: true\n"));
  PlantField field(config.plants, config.parameters);
  prepare_start(field, config.checks);
  const double reference = 5 * load / (48 * kBending);
  const double deflection = field.tip_displacement(0).y();
  std::printf("mid-length load: tip deflection %.6e m vs %.6e m (%+.3f %%)\n", deflection,
              reference, 100 * (deflection / reference - 1));
  EXPECT_NEAR(deflection / reference, 1.0, 0.005);
}

// Without static_solve a point load acts from t = 0 on the straight plant.
TEST(BeamChecks, PointLoadsWithoutStaticSolveStartStraight) {
  const VegetationConfig config =
      parse(vacuum_section(8, "    point_loads:\n      - {at: 0.5, force: [1.0e-3, 0, 0]}\n"));
  PlantField field(config.plants, config.parameters);
  prepare_start(field, config.checks);
  EXPECT_EQ(field.tip_displacement(0).norm(), 0.0);
  const auto still = testing::uniform(field, Eigen::Vector3d::Zero());
  field.advance(1e-3, still, still);
  EXPECT_GT(field.tip_displacement(0).x(), 0.0);
}

struct Oscillation {
  double frequency = 0;  // Hz, from the tip's zero crossings
  double amplitude = 0;  // m, largest |tip x|
};

// Sub-steps 20 times the axial spring-mass limit (3.1e-5 s at 32 links): the Newmark period
// error (omega dt)^2 / 12 of mode 2 (10.1 Hz) is then 1.3e-4 (cantilever.md).
const std::string kImplicitStep = "safety_factor: 20\n";

Oscillation tip_oscillation(PlantField& field, double period, int periods) {
  const double window = period / 50;
  const auto still = testing::uniform(field, Eigen::Vector3d::Zero());
  Oscillation result;
  int crossings = 0;
  double first = 0, last = 0, previous = field.tip_displacement(0).x();
  for (int w = 0; w < 50 * periods; ++w) {
    field.advance(window, still, still);
    const double x = field.tip_displacement(0).x();
    result.amplitude = std::max(result.amplitude, std::abs(x));
    if ((previous > 0) != (x > 0)) {
      const double t = field.time() - window * x / (x - previous);
      if (crossings == 0) first = t;
      last = t;
      ++crossings;
    }
    previous = x;
  }
  result.frequency = 0.5 * (crossings - 1) / (last - first);
  return result;
}

// Released from the static deflection of a small tip force: undamped free vibration at the
// first clamped-free frequency (cantilever.md, 16 links within 1 %) with the static deflection
// as amplitude.
TEST(BeamChecks, PluckByTipForceVibratesAtTheFirstFrequencyWithTheStaticAmplitude) {
  const double force = 3 * kBending * 1e-4;  // static tip deflection 1e-4 L
  const VegetationConfig config = parse(vacuum_section(
      16, "    pluck: {tip_force: [" + std::to_string(force) + ", 0, 0]}\n", kImplicitStep));
  PlantField field(config.plants, config.parameters);
  const StartReport start = prepare_start(field, config.checks);
  EXPECT_GT(start.static_iterations, 0);
  const double f1 = cantilever_frequency(1, kBending, kMassPerLength, 1.0);
  const Oscillation motion = tip_oscillation(field, 1 / f1, 10);
  std::printf("tip-force pluck: %.5f Hz vs %.5f Hz (%+.3f %%), amplitude %.5e m vs %.5e m\n",
              motion.frequency, f1, 100 * (motion.frequency / f1 - 1), motion.amplitude,
              force / (3 * kBending));
  EXPECT_NEAR(motion.frequency / f1, 1.0, 0.01);
  EXPECT_NEAR(motion.amplitude / (force / (3 * kBending)), 1.0, 0.01);
}

// Started straight in the velocity shape of mode 1 (or 2) with tip speed v: the tip moves as
// (v / omega_n) sin(omega_n t), only mode n being excited.
TEST(BeamChecks, PluckByModeVelocityVibratesInThatMode) {
  for (const int mode : {1, 2}) {
    const double speed = 1e-3;
    const VegetationConfig config =
        parse(vacuum_section(32,
                             "    pluck: {mode: " + std::to_string(mode) + ", tip_velocity: [" +
                                 std::to_string(speed) + ", 0, 0]}\n",
                             kImplicitStep));
    PlantField field(config.plants, config.parameters);
    const StartReport start = prepare_start(field, config.checks);
    ASSERT_EQ(start.pluck_tip_velocities.size(), 1u);
    EXPECT_NEAR((start.pluck_tip_velocities[0] - Eigen::Vector3d(speed, 0, 0)).norm(), 0.0,
                1e-9 * speed);
    const double f = cantilever_frequency(mode, kBending, kMassPerLength, 1.0);
    const Oscillation motion = tip_oscillation(field, 1 / f, 10);
    const double amplitude = speed / (2 * std::numbers::pi * f);
    std::printf(
        "mode %d velocity pluck: %.5f Hz vs %.5f Hz (%+.3f %%), amplitude %.5e m vs "
        "%.5e m\n",
        mode, motion.frequency, f, 100 * (motion.frequency / f - 1), motion.amplitude, amplitude);
    EXPECT_NEAR(motion.frequency / f, 1.0, 0.01) << "mode " << mode;
    EXPECT_NEAR(motion.amplitude / amplitude, 1.0, 0.01) << "mode " << mode;
  }
}

// modes: 3 gives the first three clamped-free frequencies (cantilever.md), here in water with
// the added mass C_M rho A (32 links, within 1 %).
TEST(BeamChecks, ModesKeyGivesTheCantileverFrequencies) {
  std::string yaml = vacuum_section(32, "", "modes: 3\n");
  yaml.replace(yaml.find("fluid_density: 0"), 16, "fluid_density: 1000");
  const VegetationConfig config = parse(yaml);
  EXPECT_EQ(config.checks.modes, 3);
  PlantField field(config.plants, config.parameters);
  prepare_start(field, config.checks);
  const auto frequencies = modal_frequencies(field, config.checks.modes);
  ASSERT_EQ(frequencies.size(), 1u);
  ASSERT_EQ(frequencies[0].size(), 3u);
  for (int mode = 1; mode <= 3; ++mode) {
    const double reference = cantilever_frequency(mode, kBending, 2 * kMassPerLength, 1.0);
    std::printf("mode %d: %.5f Hz vs %.5f Hz (%+.3f %%)\n", mode, frequencies[0][mode - 1],
                reference, 100 * (frequencies[0][mode - 1] / reference - 1));
    EXPECT_NEAR(frequencies[0][mode - 1] / reference, 1.0, 0.01) << "mode " << mode;
  }
}

TEST(BeamChecks, BadKeysAreScenarioErrorsWithFileLineAndKey) {
  const struct {
    std::string extra, section_extra, key, problem;
  } cases[] = {
      {"    point_loads:\n      - {at: 0.0, force: [1, 0, 0]}\n", "", "plants[0].point_loads[0].at",
       "out of range (0, 1]"},
      {"    point_loads:\n      - {at: 0.01, force: [1, 0, 0]}\n", "",
       "plants[0].point_loads[0].at", "clamped base"},
      {"    point_loads:\n      - {at: 1, force: [1.0e7, 0, 0]}\n", "",
       "plants[0].point_loads[0].force", "at most"},
      {"    pluck: {tip_force: [1, 0, 0], tip_velocity: [1, 0, 0]}\n", "",
       "plants[0].pluck.tip_velocity", "give one of"},
      {"    pluck: {mode: 2}\n", "", "plants[0].pluck.tip_force", "give one of"},
      {"    pluck: {mode: 11, tip_velocity: [1, 0, 0]}\n", "", "plants[0].pluck.mode",
       "out of range [1, 10]"},
      // Mode 1 bends the plant: it cannot move the tip along the plant.
      {"    pluck: {tip_velocity: [0, 0, 1.0e-3]}\n", "", "plants[0].pluck.tip_velocity",
       "moves its tip at best"},
      {"", "modes: 21\n", "modes", "out of range [0, 20]"},
      {"", "newton_tolerance: 0.01\n", "newton_tolerance", "out of range (0, 0.001]"},
      {"", "newton_tolerance: 0\n", "newton_tolerance", "out of range"},
      {"", "max_newton_iterations: 0\n", "max_newton_iterations", "out of range [1, 1000]"},
  };
  for (const auto& c : cases) {
    const std::string message = parse_error(vacuum_section(8, c.extra, c.section_extra));
    EXPECT_NE(message.find("checks.yaml:"), std::string::npos) << message;
    EXPECT_NE(message.find("key '" + c.key + "'"), std::string::npos) << message;
    EXPECT_NE(message.find(c.problem), std::string::npos) << message;
  }
}

TEST(BeamChecks, NewtonKeysReachThePlantSolver) {
  const VegetationConfig config =
      parse(vacuum_section(8, "", "newton_tolerance: 1.0e-8\nmax_newton_iterations: 50\n"));
  EXPECT_EQ(config.parameters.newton_tolerance, 1e-8);
  EXPECT_EQ(config.parameters.max_newton_iterations, 50);
  const VegetationConfig defaults = parse(vacuum_section(8, ""));
  EXPECT_EQ(defaults.parameters.newton_tolerance, 1e-10);
  EXPECT_EQ(defaults.parameters.max_newton_iterations, 20);
  EXPECT_FALSE(defaults.checks.static_solve);
  EXPECT_EQ(defaults.checks.modes, 0);
}

}  // namespace
}  // namespace cosim::vegetation
