// The Newton solve of the implicit sub-step far above the spring-mass step limit (safety_factor
// up to the 1000 the scenario allows), and what a failure reports.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "beam_test_helpers.hpp"

namespace cosim::vegetation {
namespace {

using testing::pet_strip;

// 20 PET strips 1 cm apart across the stream, upright or leaning 10 or 20 degrees: they never
// touch.
std::vector<PlantSpec> free_strips() {
  std::vector<PlantSpec> specs;
  for (int k = 0; k < 20; ++k) {
    PlantSpec blade = pet_strip(1380, 10.0 * (k % 3));
    blade.base = Eigen::Vector3d(0, 0.01 * k, 0);
    specs.push_back(blade);
  }
  return specs;
}

BeamParameters water(double safety_factor) {
  return testing::pet_strip_water(safety_factor);
}

// A light blade (10 kg/m^3) leaning 45 degrees in still water: its net buoyancy, 99 % of the
// displaced weight, acts as a step at t = 0. In 0.05 s windows it settled where the static
// solve puts it at every factor; before the robust Newton attempt it failed the first sub-step
// at safety_factor 300 and 1000 (modified Newton from the constant-acceleration predictor
// contracted by only 0.56 per iteration at 500).
TEST(NewtonAtLargeSubsteps, BuoyancyStepAtTimeZeroConvergesUpToSafetyFactor1000) {
  PlantField statics({pet_strip(10, 45)}, water(1));
  statics.solve_static();
  const Eigen::Vector3d target = statics.tip_displacement(0);
  for (const double safety_factor : {100.0, 300.0, 1000.0}) {
    PlantField field({pet_strip(10, 45)}, water(safety_factor));
    const auto still = testing::uniform(field, Eigen::Vector3d::Zero());
    int restarts = 0, cutbacks = 0, substeps = 0;
    for (int window = 0; window < 60; ++window) {
      const WindowReport report = field.advance(0.05, still, still);
      restarts += report.newton_restarts;
      cutbacks += report.cutbacks;
      substeps += report.substeps;
    }
    const Eigen::Vector3d tip = field.tip_displacement(0);
    std::printf(
        "safety_factor %4.0f: %5d sub-steps, %2d robust restarts, %d cutbacks; tip (%.4e, "
        "%.4e) m, static (%.4e, %.4e) m\n",
        safety_factor, substeps, restarts, cutbacks, tip.x(), tip.z(), target.x(), target.z());
    EXPECT_LT((tip - target).norm(), 1e-3 * target.norm()) << "safety_factor " << safety_factor;
  }
}

// The blade of the single-blade scene started from rest in a 3.83 m/s stream (Cauchy number
// 3000): it is laid flat within about 10 ms, further than Newton reaches in one sub-step above
// safety_factor 30 from either predictor. The sub-steps are halved until it converges, and the
// steady shape is that of the resolved run.
TEST(NewtonAtLargeSubsteps, AnImpulsiveStartIsCarriedByHalvedSubsteps) {
  const double speed = 3.826;
  Eigen::Vector3d tips[2];
  int cutbacks = 0;
  for (int run = 0; run < 2; ++run) {
    PlantField field({pet_strip(1390, 0)}, water(run == 0 ? 10 : 300));
    const auto flow = testing::uniform(field, Eigen::Vector3d(speed, 0, 0));
    for (int window = 0; window < 30; ++window)
      cutbacks += field.advance(0.01, flow, flow).cutbacks;
    tips[run] = field.tip_displacement(0);
  }
  std::printf("tip at safety_factor 10 (%.6f, %.6f) m, at 300 (%.6f, %.6f) m, %d cutbacks\n",
              tips[0].x(), tips[0].z(), tips[1].x(), tips[1].z(), cutbacks);
  EXPECT_GT(cutbacks, 0);
  EXPECT_LT((tips[1] - tips[0]).norm(), 1e-4 * tips[0].norm());
}

// A Newton failure names the plant and node of the largest residual and the keys to change.
// Plant 1 carries a 1 N point load on node 5 only, in vacuum, with sub-steps 100 times the
// spring-mass limit; with one Newton iteration allowed no attempt converges, even halved 6
// times. From rest the residual m a - F of the robust attempt is -2 F at the loaded node and
// zero elsewhere (Newmark's a = -a0 with a0 = F / m), so node 5 it must be.
TEST(NewtonFailure, NamesThePlantAndNodeOfTheLargestResidualAndTheKeys) {
  BeamParameters parameters = testing::vacuum_parameters();
  parameters.max_newton_iterations = 1;
  parameters.safety_factor = 100;
  parameters.contact = false;
  PlantSpec b = testing::textbook_strip(10);
  b.base = Eigen::Vector3d(1, 0, 0);
  PlantField field({testing::textbook_strip(10), b}, parameters);
  std::vector<Eigen::Vector3d> loads(field.node_count(), Eigen::Vector3d::Zero());
  loads[field.node_range(1).first + 5] = Eigen::Vector3d(1.0, 0, 0);
  field.set_external_forces(loads);
  const auto still = testing::uniform(field, Eigen::Vector3d::Zero());
  try {
    field.advance(0.1, still, still);
    FAIL() << "expected StabilityError";
  } catch (const StabilityError& error) {
    const std::string message = error.what();
    std::printf("%s\n", message.c_str());
    EXPECT_NE(message.find("plant 1 node 5:"), std::string::npos) << message;
    EXPECT_NE(message.find("residual |m a - F| 2 N"), std::string::npos) << message;
    for (const char* key : {"safety_factor", "max_newton_iterations = 1", "newton_tolerance"})
      EXPECT_NE(message.find(key), std::string::npos) << key << ": " << message;
  }
}

// From 16 plants out of contact on, their Newton iterations run side by side (OpenMP); plants
// in contact follow in index order. A field of 20 free strips and two touching ones: the same
// bits with one and two threads. (The free strips are not compared with a field without the
// pair: the sub-step, its restarts and cutbacks are the field's, so the pair changes them too.)
TEST(NewtonSideBySide, SameBitsWithOneAndTwoThreads) {
  std::vector<PlantSpec> specs = free_strips();
  for (int k = 0; k < 2; ++k) {  // 1.5 mm apart: the 2 mm wide strips touch at once
    PlantSpec blade = pet_strip(1380, 0.0);
    blade.base = Eigen::Vector3d(0.0015 * k, 0.5, 0);
    specs.push_back(blade);
  }
  int most_in_contact = 0;
  const auto run = [&](int threads) {
    omp_set_num_threads(threads);
    PlantField field(specs, water(10));
    const auto flow = testing::uniform(field, Eigen::Vector3d(0.15, 0, 0));
    for (int window = 0; window < 4; ++window) {
      const WindowReport report = field.advance(0.002, flow, flow);
      most_in_contact = std::max(most_in_contact, report.most_plants_in_contact);
    }
    return field.positions();
  };
  const int threads = omp_get_max_threads();
  const auto one = run(1), two = run(2);
  omp_set_num_threads(threads);
  ASSERT_EQ(one.size(), two.size());
  for (std::size_t k = 0; k < one.size(); ++k) {
    for (int d = 0; d < 3; ++d) ASSERT_EQ(one[k][d], two[k][d]) << "node " << k;
  }
  // The pair did touch: contact pushed the tips of strips whose bases are 1.5 mm apart apart.
  const std::size_t nodes = 17, first_of_pair = 20 * nodes;
  const double tip_gap =
      (one[first_of_pair + 2 * nodes - 1] - one[first_of_pair + nodes - 1]).norm();
  std::printf("tips of the touching pair %.3f mm apart\n", 1e3 * tip_gap);
  EXPECT_GT(tip_gap, 0.0017);
  EXPECT_EQ(most_in_contact, 2);  // the pair, and none of the free strips
}

// reuse_jacobian keeps each plant's factorised Jacobian over the later sub-steps of a window:
// one factorisation per plant and window instead of one per sub-step, and the same motion to
// the Newton tolerance. 20 strips at safety_factor 10 in a 0.15 m/s stream, 20 windows of 2 ms.
TEST(NewtonKeptJacobian, OneFactorisationPerPlantAndWindowAndTheSameMotion) {
  std::vector<PlantSpec> specs = free_strips();
  struct Run {
    std::vector<Eigen::Vector3d> positions;
    int substeps = 0, factorizations = 0;
  };
  const auto run = [&](bool reuse) {
    BeamParameters parameters = water(10);
    parameters.reuse_jacobian = reuse;
    PlantField field(specs, parameters);
    const auto flow = testing::uniform(field, Eigen::Vector3d(0.15, 0, 0));
    Run out;
    for (int window = 0; window < 20; ++window) {
      const WindowReport report = field.advance(0.002, flow, flow);
      EXPECT_EQ(report.newton_restarts, 0);
      EXPECT_EQ(report.cutbacks, 0);
      EXPECT_EQ(report.most_plants_in_contact, 0);  // kept Jacobians need plants out of contact
      out.substeps += report.substeps;
      out.factorizations += report.factorizations;
    }
    out.positions = field.positions();
    return out;
  };
  const Run fresh = run(false), kept = run(true);
  const int plants = static_cast<int>(specs.size());
  ASSERT_GT(fresh.substeps, 20 * 2);  // more than one sub-step a window, else nothing is kept
  EXPECT_EQ(fresh.factorizations, plants * fresh.substeps);
  EXPECT_EQ(kept.factorizations, plants * 20);
  // Each sub-step stops once a correction is below newton_tolerance (1e-10 link lengths); the
  // two runs may differ by that much a sub-step.
  const double link = 0.045 / 16, bound = 1e-10 * link * fresh.substeps;
  double largest = 0;
  for (std::size_t k = 0; k < fresh.positions.size(); ++k)
    largest = std::max(largest, (fresh.positions[k] - kept.positions[k]).norm());
  std::printf("%d sub-steps; largest node distance %.3g m (bound %.3g m)\n", fresh.substeps,
              largest, bound);
  EXPECT_LT(largest, bound);
  EXPECT_GT(largest, 0.0);  // not trivially the same run
}

}  // namespace
}  // namespace cosim::vegetation
