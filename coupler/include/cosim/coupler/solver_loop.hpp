// The one window loop every solver process runs. A process main only adapts its physics library
// to `Solver`; the loop owns the order of a window (fault injection, window 0, advance, output
// timing, done) and the final report, so every participant keeps the same protocol.
#pragma once

#include "cosim/checkpoint/archive.hpp"
#include "cosim/coupler/metrics.hpp"
#include "cosim/coupler/process_main.hpp"

namespace cosim::coupler {

struct WindowResult {
  int steps = 0;           // solver steps (sub-steps for sub-cycling solids) in the window
  double stable_dt = 0.0;  // largest next window the solver accepts; 0: no limit
};

class Solver {
 public:
  virtual ~Solver() = default;
  // Window 0 (dt = 0): exchange initial states.
  virtual WindowResult initial_window(const Window& window) = 0;
  // Window k >= 1: take the partners' fields, advance over [t, t + dt], publish.
  virtual WindowResult advance(const Window& window) = 0;
  // Time of the solver's state since the run started [s], for output timing.
  virtual double output_time() const = 0;
  // One output frame of the current state.
  virtual void write_output() {}
  // The window just advanced is final: explicit schemes at once, implicit ones once the coupler
  // accepted it (its last iteration's state is current). Records written once a window (a CSV
  // row) belong here, not in advance(), which an implicit scheme runs once an iteration.
  virtual void window_accepted() {}
  // After the last window: final outputs and the metrics report.
  virtual void finish(MetricsReport& report) = 0;
  // The full state after the window just done (physics through its library's checkpoint code,
  // plus the process's own running totals), and reading it back into a solver built from the
  // same scene. A solver that keeps nothing across windows writes nothing.
  virtual void save_checkpoint(checkpoint::Writer& /*out*/) const {}
  virtual void load_checkpoint(const checkpoint::Reader& /*in*/) {}
};

// Output frames: one at window 0, one each time output_time() reaches a multiple of `interval`
// (no drift over long runs; several windows per interval or several intervals per window both
// give one frame per crossing), and the final state at FINISH unless it was just written.
// interval <= 0: no frames.
//
// Checkpoints: when the coupler asks for one after window N, the loop writes
// checkpoints/window_N/<name>.ckpt: the solver's state, the output clock, and the fields the
// participant published in window N. A process started with --restart loads that file, and its
// first window is N again (dt 0): it publishes the saved fields instead of computing, so its
// partners' window N + 1 reads what it read in the uninterrupted run.
void run_solver_loop(ProcessContext& context, Solver& solver, double interval);

}  // namespace cosim::coupler
