// How the solvers' OpenMP threads wait between parallel regions: set once for every process a
// run starts (`cosim run`, `cosim join`), before the OpenMP runtime reads it.
#pragma once

#include <functional>
#include <string>
#include <vector>

namespace cosim::tool {

struct EnvironmentSetting {
  std::string name, value;
};

// libgomp spin count of the default wait: about 0.1 ms (libgomp counts about 100 000 spins a
// millisecond) before a waiting thread sleeps. Measured in docs/performance.md (fluid_mps, "How
// the threads wait"): a 2D step of 17 k particles on 2 threads of an idle machine took 39 ms with
// threads that sleep at once and 22 ms with this bound; with four busy processes on the two
// cores, 37 against 56-88 ms, which is why a shared machine should set OMP_WAIT_POLICY=passive.
inline constexpr const char* kBoundedSpinCount = "10000";

// The settings to add to the environment, given how it reads now (`lookup` returns null for an
// unset name): none if the user chose a wait (OMP_WAIT_POLICY or GOMP_SPINCOUNT set); otherwise
// a short bounded spin in libgomp (GOMP_SPINCOUNT), and OMP_WAIT_POLICY=passive for the other
// OpenMP runtimes, whose default would spin for much longer.
std::vector<EnvironmentSetting> thread_wait_settings(
    const std::function<const char*(const char*)>& lookup);

// Applies thread_wait_settings() of this process's environment to it; the processes it starts
// inherit it.
void set_thread_wait();

}  // namespace cosim::tool
