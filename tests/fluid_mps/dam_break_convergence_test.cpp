// Martin & Moyce dam break at a/l0 = 10, 15, 20 (label slow): the error against the experiment
// must not grow with resolution, and the error/run-time table is printed.
#include <gtest/gtest.h>

#include <iomanip>

#include "dam_break_case.hpp"

using namespace cosim::mps;
using namespace cosim::mps::testing;

TEST(MpsDamBreak, MartinMoyceResolutionSweep) {
  const std::string reference = std::string(COSIM_SHARED_REFERENCES) + "/martin_moyce_1952.csv";
  std::vector<DamBreakResult> results;
  const std::vector<int> resolutions{10, 15, 20};
  for (int cells : resolutions) results.push_back(run_dam_break(cells, 0.35, reference));
  std::cout << "a/l0  particles  steps  wall[s]   cpu[s]  front_rms[%]  height_rms[%]\n";
  for (std::size_t k = 0; k < results.size(); ++k) {
    const auto& r = results[k];
    std::cout << std::setw(4) << resolutions[k] << std::setw(11) << r.particles << std::setw(7)
              << r.steps << std::setw(9) << std::setprecision(3) << r.wall_seconds << std::setw(14)
              << 100 * r.front_rms << std::setw(15) << 100 * r.height_rms << "\n";
  }
  for (const auto& r : results) {
    EXPECT_LT(r.front_rms, 0.15);
    EXPECT_LT(r.height_rms, 0.15);
  }
  // Loose: the finest run is no worse than the coarsest (plus a 2-point allowance for noise).
  EXPECT_LE(results.back().front_rms, results.front().front_rms + 0.02);
  EXPECT_LE(results.back().height_rms, results.front().height_rms + 0.02);
}
