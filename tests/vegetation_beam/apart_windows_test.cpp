// Windows solved plant by plant (plant_field_apart.cpp) against the sub-step-synchronous path:
// the same bits whether a window goes plant by plant, falls back, or never tries.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

#include "beam_test_helpers.hpp"

namespace cosim::vegetation {
namespace {

using testing::pet_strip;

BeamParameters water(double safety_factor, bool apart) {
  BeamParameters parameters = testing::pet_strip_water(safety_factor);
  parameters.plants_apart_windows = apart;
  return parameters;
}

struct FieldRun {
  std::vector<Eigen::Vector3d> positions, velocities, drag;
  std::vector<WindowReport> reports;
  int apart_windows = 0, most_in_contact = 0, restarts = 0;
};

// `windows` windows of `window_dt` in a stream along x whose speed changes within and between
// windows (still water for the first `still_windows`).
FieldRun run(const std::vector<PlantSpec>& specs, const BeamParameters& parameters, int windows,
             int threads, double window_dt = 0.002, int still_windows = 0) {
  const int threads_before = omp_get_max_threads();
  omp_set_num_threads(threads);
  PlantField field(specs, parameters);
  FieldRun out;
  for (int window = 0; window < windows; ++window) {
    const auto speed = [&](int w) { return w < still_windows ? 0.0 : 0.15 + 0.02 * std::sin(w); };
    const auto begin = testing::uniform(field, Eigen::Vector3d(speed(window), 0, 0));
    const auto end = testing::uniform(field, Eigen::Vector3d(speed(window + 1), 0, 0));
    out.reports.push_back(field.advance(window_dt, begin, end));
    const WindowReport& report = out.reports.back();
    out.apart_windows += report.plants_apart ? 1 : 0;
    out.most_in_contact = std::max(out.most_in_contact, report.most_plants_in_contact);
    out.restarts += report.newton_restarts;
  }
  out.positions = field.positions();
  out.velocities = field.velocities();
  out.drag = field.window_mean_drag();
  omp_set_num_threads(threads_before);
  return out;
}

void expect_same_bits(const FieldRun& a, const FieldRun& b) {
  ASSERT_EQ(a.positions.size(), b.positions.size());
  for (std::size_t k = 0; k < a.positions.size(); ++k) {
    for (int d = 0; d < 3; ++d) {
      ASSERT_EQ(a.positions[k][d], b.positions[k][d]) << "node " << k;
      ASSERT_EQ(a.velocities[k][d], b.velocities[k][d]) << "node " << k;
      ASSERT_EQ(a.drag[k][d], b.drag[k][d]) << "node " << k;
    }
  }
  ASSERT_EQ(a.reports.size(), b.reports.size());
  for (std::size_t w = 0; w < a.reports.size(); ++w) {
    EXPECT_EQ(a.reports[w].substeps, b.reports[w].substeps) << "window " << w;
    EXPECT_EQ(a.reports[w].max_newton_iterations, b.reports[w].max_newton_iterations)
        << "window " << w;
    EXPECT_EQ(a.reports[w].factorizations, b.reports[w].factorizations) << "window " << w;
    EXPECT_EQ(a.reports[w].newton_restarts, b.reports[w].newton_restarts) << "window " << w;
    EXPECT_EQ(a.reports[w].most_plants_in_contact, b.reports[w].most_plants_in_contact)
        << "window " << w;
  }
}

// 20 strips 1 cm apart across the stream, upright or leaning 10 or 20 degrees: they never touch,
// and every window goes plant by plant, on one thread and on two.
TEST(PlantsApart, FreePlantsGoPlantByPlantWithTheSynchronousBits) {
  std::vector<PlantSpec> specs;
  for (int k = 0; k < 20; ++k)
    specs.push_back(pet_strip(1380, 10.0 * (k % 3), Eigen::Vector3d(0, 0.01 * k, 0)));
  const FieldRun synchronous = run(specs, water(10, false), 30, 2);
  const FieldRun one = run(specs, water(10, true), 30, 1), two = run(specs, water(10, true), 30, 2);
  EXPECT_EQ(synchronous.apart_windows, 0);
  EXPECT_EQ(one.apart_windows, 30);
  EXPECT_EQ(two.apart_windows, 30);
  ASSERT_GT(synchronous.reports[0].substeps, 1);  // windows of several sub-steps
  expect_same_bits(synchronous, one);
  expect_same_bits(synchronous, two);
}

// Pairs of strips along the stream, 7 mm apart: a pair within reach plus the clearance margin
// (2 + 4 mm) keeps a window synchronous, so they start clear. The downstream strip is a hundred
// times stiffer, and the upstream one bends onto it: windows go plant by plant, then
// synchronously as the gaps close and the strips touch. The contact sums after the apart windows
// read the candidate list the synchronous path would have built.
TEST(PlantsApart, PlantsThatComeToTouchFallBackWithTheSynchronousBits) {
  std::vector<PlantSpec> specs;
  for (int k = 0; k < 10; ++k) {
    specs.push_back(pet_strip(1380, 0.0, Eigen::Vector3d(0, 0.03 * k, 0)));
    PlantSpec stiff = pet_strip(1380, 0.0, Eigen::Vector3d(0.007, 0.03 * k, 0));
    stiff.bending_stiffness *= 100;
    specs.push_back(stiff);
  }
  const FieldRun synchronous = run(specs, water(50, false), 80, 2);
  const FieldRun apart = run(specs, water(50, true), 80, 2);
  std::printf("%d of 80 windows plant by plant; %d plants in contact at most\n",
              apart.apart_windows, apart.most_in_contact);
  EXPECT_GT(apart.apart_windows, 0);
  EXPECT_LT(apart.apart_windows, 80);
  EXPECT_GT(apart.most_in_contact, 0);
  expect_same_bits(synchronous, apart);
}

// Light strips (10 kg/m^3) leaning 45 degrees, released in still water at safety_factor 400 in
// 0.05 s windows; the stream starts over the third window. There the fast Newton attempt fails
// (as in NewtonAtLargeSubsteps), so that window falls back to the synchronous path and its robust
// attempt; the window after it is solved synchronously at once, and later windows go plant by
// plant again.
TEST(PlantsApart, AWindowNeedingTheRobustAttemptFallsBackWithTheSynchronousBits) {
  std::vector<PlantSpec> specs;
  for (int k = 0; k < 20; ++k) specs.push_back(pet_strip(10, 45, Eigen::Vector3d(0, 0.05 * k, 0)));
  const FieldRun synchronous = run(specs, water(400, false), 40, 2, 0.05, 3);
  const FieldRun apart = run(specs, water(400, true), 40, 2, 0.05, 3);
  std::printf("%d of 40 windows plant by plant; %d robust restarts\n", apart.apart_windows,
              apart.restarts);
  std::size_t robust = 0;
  while (robust < apart.reports.size() && apart.reports[robust].newton_restarts == 0) ++robust;
  ASSERT_LT(robust + 1, apart.reports.size()) << "no window needed the robust attempt";
  std::printf("window %zu needed the robust attempt\n", robust);
  EXPECT_FALSE(apart.reports[robust].plants_apart);      // fell back
  EXPECT_FALSE(apart.reports[robust + 1].plants_apart);  // synchronous at once after it
  EXPECT_GT(apart.apart_windows, 30);
  expect_same_bits(synchronous, apart);
}

}  // namespace
}  // namespace cosim::vegetation
