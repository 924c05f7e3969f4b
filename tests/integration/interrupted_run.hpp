// A `cosim run` stopped by SIGINT (a user's Ctrl-C), for the restart tests of explicit and
// implicit runs.
#pragma once

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include "command.hpp"

namespace cosim::testing {

struct InterruptedRun {
  std::filesystem::path folder;
  double checkpoint_time = -1.0;  // [s] of the one checkpoint it saved; < 0 when it saved none
};

// `cosim ARGUMENTS`, interrupted after `seconds`: it exits with 130, says SIGINT in summary.json
// and saved exactly one checkpoint (failures are recorded in the calling test).
inline InterruptedRun interrupted_run(const std::string& arguments, int seconds) {
  InterruptedRun run;
  const auto result = interrupt_cosim(arguments, seconds);
  EXPECT_EQ(result.exit_code, 130) << result.output;
  run.folder = run_folder_of(result);
  if (run.folder.empty()) {
    ADD_FAILURE() << "no run folder: " << result.output;
    return run;
  }
  const auto summary = read_summary(run.folder);
  EXPECT_EQ(summary["interrupted_by"], "SIGINT");
  if (summary["checkpoints"].size() != 1u) {
    ADD_FAILURE() << "expected one checkpoint: " << summary.dump(2);
    return run;
  }
  run.checkpoint_time = summary["checkpoints"][0]["time"].get<double>();
  std::printf("interrupted; checkpoint after window %lld (t = %.6g s)\n",
              static_cast<long long>(summary["checkpoints"][0]["window"].get<int64_t>()),
              run.checkpoint_time);
  return run;
}

}  // namespace cosim::testing
