#include "cosim/coupler/solver_loop.hpp"

#include <cmath>
#include <limits>

namespace cosim::coupler {

namespace {

// Frames at multiples of the interval, compared with a tolerance relative to the interval.
class OutputClock {
 public:
  explicit OutputClock(double interval) : interval_(interval) {}
  bool due(double time) const { return interval_ > 0.0 && time >= next_ - 1e-9 * interval_; }
  void written(double time) {
    last_ = time;
    next_ = interval_ * (std::floor(time / interval_ + 1e-9) + 1.0);
  }
  bool written_at(double time) const {
    return std::abs(time - last_) <= 1e-12 * std::max(1.0, std::abs(time));
  }

 private:
  double interval_;
  double next_ = 0.0;
  double last_ = -std::numeric_limits<double>::infinity();
};

}  // namespace

void run_solver_loop(ProcessContext& context, Solver& solver, double interval) {
  Participant& participant = *context.participant;
  OutputClock clock(interval);
  auto write_if_due = [&] {
    if (!clock.due(solver.output_time())) return;
    solver.write_output();
    clock.written(solver.output_time());
  };
  while (true) {
    const Window window = participant.next_window();
    context.maybe_inject_fault(window.index);
    if (window.finish) {
      if (interval > 0.0 && !clock.written_at(solver.output_time())) solver.write_output();
      MetricsReport report;
      solver.finish(report);
      participant.finished(report.dump());
      return;
    }
    const WindowResult result =
        window.index == 0 ? solver.initial_window(window) : solver.advance(window);
    write_if_due();
    participant.done(result.steps, result.stable_dt);
  }
}

}  // namespace cosim::coupler
