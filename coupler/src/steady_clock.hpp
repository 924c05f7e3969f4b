// The clock of every timeout, resend interval and overhead figure in coupler/src (private).
#pragma once

#include <chrono>

namespace cosim::coupler {

using Clock = std::chrono::steady_clock;

// [s] elapsed on the steady clock since `start`.
inline double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// [s] from `from` to `to` on the steady clock.
inline double seconds_between(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}

}  // namespace cosim::coupler
