// `cosim replay`: drives one real solver with every partner replayed from a recorded run, and
// checks that it says exactly what it said then, bit for bit.
#pragma once

#include <filesystem>
#include <string>

#include "runner.hpp"

namespace cosim::tool {

struct ReplayRequest {
  std::filesystem::path recorded_run;
  std::string participant;  // the solver to drive (its key or the name it acts as)
  RunRequest run;
};

// Returns the exit code: 0 identical, 1 different or failed.
int replay_run(const ReplayRequest& request);

}  // namespace cosim::tool
