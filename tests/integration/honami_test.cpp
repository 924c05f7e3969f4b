// The honami scene at CI size (seed 000 section 4): the MPS open channel drives ten flexible
// reeds. The stream must lay the plants over downstream, and the canopy outputs (psi, the tip
// amplitude and the tip time series) must be written and physically bounded.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "command.hpp"

namespace cosim::testing {
namespace {

struct Table {
  std::vector<std::string> header;
  std::vector<std::vector<double>> rows;
};

Table read_csv(const std::filesystem::path& path) {
  Table table;
  std::ifstream in(path);
  std::string line;
  if (!std::getline(in, line)) return table;
  std::stringstream header(line);
  for (std::string cell; std::getline(header, cell, ',');) table.header.push_back(cell);
  while (std::getline(in, line)) {
    std::stringstream row(line);
    std::vector<double> values;
    for (std::string cell; std::getline(row, cell, ',');) values.push_back(std::stod(cell));
    table.rows.push_back(values);
  }
  return table;
}

double metric(const nlohmann::json& participant, const std::string& name) {
  return participant["report"]["metrics"][name]["value"].get<double>();
}

class HonamiSmall : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const auto runs = fresh_folder("honami");
    result_ =
        new CommandResult(run_cosim(fmt::format("run {} --runs-dir {} --quiet",
                                                test_scene("honami_small").string(), runs.string()),
                                    300));
    run_ = run_folder_of(*result_);
  }
  static void TearDownTestSuite() {
    delete result_;
    result_ = nullptr;
  }
  void SetUp() override { ASSERT_EQ(result_->exit_code, 0) << result_->output; }

  static constexpr int kPlants = 10;
  static constexpr double kDuration = 1.5, kTipInterval = 0.05, kHeight = 1.0;
  static CommandResult* result_;
  static std::filesystem::path run_;
};

CommandResult* HonamiSmall::result_ = nullptr;
std::filesystem::path HonamiSmall::run_;

TEST_F(HonamiSmall, TheStreamLaysThePlantsOverDownstream) {
  const auto summary = read_summary(run_);
  const auto& plants = summary["participants"][1];
  ASSERT_EQ(plants["name"], "vegetation_beam");
  const double displacement = metric(plants, "mean_tip_displacement");
  // 3 m/s on a reed with EI = 0.847 N m^2: far more drag than the stem can stand upright
  // against, but a tip can never travel further than the plant is long.
  EXPECT_GT(displacement, 0.1 * kHeight);
  EXPECT_LT(displacement, kHeight);
  const double amplitude = metric(plants, "mean_tip_amplitude");
  EXPECT_GT(amplitude, 0.0);
  EXPECT_LT(amplitude, kHeight);
}

TEST_F(HonamiSmall, PsiIsFiniteAndBounded) {
  const auto summary = read_summary(run_);
  const auto& plants = summary["participants"][1];
  const double psi_min = metric(plants, "psi_min"), psi_max = metric(plants, "psi_max");
  ASSERT_TRUE(std::isfinite(psi_min) && std::isfinite(psi_max));
  EXPECT_GE(psi_min, -1.0);  // a node cannot lose more than all of its neighbours
  EXPECT_LE(psi_min, psi_max);
  EXPECT_LT(psi_max, 50.0);  // no node pile-up (contact keeps stems apart)
  EXPECT_GT(psi_max - psi_min, 0.0) << "bent plants change the vegetation density";
}

TEST_F(HonamiSmall, TipSeriesHasOneRowPerIntervalAndBendsDownstream) {
  const Table tips = read_csv(run_ / "vegetation_beam" / "tips.csv");
  ASSERT_EQ(tips.header.size(), static_cast<std::size_t>(kPlants + 1));
  EXPECT_EQ(tips.header.front(), "time");
  EXPECT_EQ(tips.header.back(), fmt::format("plant_{}", kPlants - 1));
  const int expected = static_cast<int>(std::lround(kDuration / kTipInterval)) + 1;
  EXPECT_NEAR(static_cast<double>(tips.rows.size()), expected, 1.0);
  double previous = -1.0;
  for (const auto& row : tips.rows) {
    ASSERT_EQ(row.size(), tips.header.size());
    EXPECT_GT(row[0], previous);
    previous = row[0];
  }
  for (int plant = 1; plant <= kPlants; ++plant) {
    EXPECT_EQ(tips.rows.front()[plant], 0.0) << "plants start upright";
    EXPECT_GT(tips.rows.back()[plant], 0.1 * kHeight) << "plant " << plant - 1;
  }
  // Laid over, the tips come down: the height series has the same shape and negative values.
  const Table heights = read_csv(run_ / "vegetation_beam" / "tip_heights.csv");
  ASSERT_EQ(heights.rows.size(), tips.rows.size());
  for (int plant = 1; plant <= kPlants; ++plant) {
    EXPECT_LT(heights.rows.back()[plant], 0.0) << "plant " << plant - 1;
    EXPECT_GT(heights.rows.back()[plant], -kHeight) << "plant " << plant - 1;
  }
}

}  // namespace
}  // namespace cosim::testing
