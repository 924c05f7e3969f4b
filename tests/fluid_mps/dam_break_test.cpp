// Martin & Moyce dam break at the resolutions listed in COSIM_MPS_DAM_BREAK_RESOLUTIONS.
#include <gtest/gtest.h>

#include "dam_break_case.hpp"

using namespace cosim::mps;
using namespace cosim::mps::testing;

namespace {
const std::string kReference = std::string(COSIM_SHARED_REFERENCES) + "/martin_moyce_1952.csv";
constexpr double kEndTime = 0.35;  // tau = 4.6, T = 6.5: the front has reached the far wall
}  // namespace

TEST(MpsDamBreak, MartinMoyceCoarse) {
  const DamBreakResult r = run_dam_break(10, kEndTime, kReference);
  EXPECT_LT(r.front_rms, 0.15);
  EXPECT_LT(r.height_rms, 0.15);
}
