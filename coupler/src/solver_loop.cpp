#include "cosim/coupler/solver_loop.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

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
  void save(checkpoint::Writer& out) const {
    out.value("loop.clock_next", next_);
    out.value("loop.clock_last", last_);
  }
  void load(const checkpoint::Reader& in) {
    next_ = in.value<double>("loop.clock_next");
    last_ = in.value<double>("loop.clock_last");
  }

 private:
  double interval_;
  double next_ = 0.0;
  double last_ = -std::numeric_limits<double>::infinity();
};

using Fields = std::vector<std::pair<std::string, std::vector<double>>>;

// What the restart window hands out again: the fields of window N and its report.
struct Restored {
  int64_t window = 0;
  double stable_dt = 0.0;
  Fields fields;
};

// `fields`: what this participant published in window `window.index` (handed out again by the
// restart window).
void write_checkpoint(ProcessContext& context, const Solver& solver, const OutputClock& clock,
                      const Window& window, const WindowResult& result, const Fields& fields) {
  const auto started = std::chrono::steady_clock::now();
  Participant& participant = *context.participant;
  checkpoint::Writer out(context.program);
  out.text("loop.acts_as", participant.name());
  out.value("loop.window", window.index);
  out.value("loop.stable_dt", result.stable_dt);
  clock.save(out);
  std::string names;
  for (const auto& [name, values] : fields) {
    names += name + '\n';
    out.vector("field." + name, values);
  }
  out.text("loop.fields", names);
  solver.save_checkpoint(out);
  const auto folder = context.checkpoint_folder(window.index);
  std::filesystem::create_directories(folder);
  const auto file = context.checkpoint_file(folder);
  const auto bytes = out.save(file);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  spdlog::info("checkpoint after window {}: {} ({} bytes, {:.3f} s)", window.index, file.string(),
               bytes, seconds);
  participant.checkpointed(
      nlohmann::json{
          {"file", file.filename().string()}, {"bytes", bytes}, {"write_seconds", seconds}}
          .dump(),
      window.index);
}

Restored read_checkpoint(ProcessContext& context, Solver& solver, OutputClock& clock) {
  const auto file = context.checkpoint_file(context.restart_dir);
  const checkpoint::Reader in(file, context.program);
  if (const auto acts_as = in.text("loop.acts_as"); acts_as != context.participant->name()) {
    in.fail("loop.acts_as", "is '" + acts_as + "', not '" + context.participant->name() + "'");
  }
  Restored restored;
  restored.window = in.value<int64_t>("loop.window");
  restored.stable_dt = in.value<double>("loop.stable_dt");
  clock.load(in);
  const std::string names = in.text("loop.fields");
  for (std::size_t at = 0; at < names.size();) {
    const auto end = names.find('\n', at);
    const std::string name = names.substr(at, end - at);
    restored.fields.emplace_back(name, in.vector<double>("field." + name));
    at = end == std::string::npos ? names.size() : end + 1;
  }
  solver.load_checkpoint(in);
  spdlog::info("restarted from {} after window {} (t = {:.9g} s)", file.string(), restored.window,
               solver.output_time());
  return restored;
}

}  // namespace

void run_solver_loop(ProcessContext& context, Solver& solver, double interval) {
  Participant& participant = *context.participant;
  OutputClock clock(interval);
  std::optional<Restored> restored;
  if (!context.restart_dir.empty()) {
    restored = read_checkpoint(context, solver, clock);
    participant.start_at(restored->window);
  }
  auto write_if_due = [&] {
    if (!clock.due(solver.output_time())) return;
    solver.write_output();
    clock.written(solver.output_time());
  };
  WindowResult last;
  // Implicit schemes run a window several times: each iteration starts from the state at the
  // window start, kept in memory in the checkpoint format (the solver's save_checkpoint), and an
  // output frame is written only once the coupler has accepted the window (when the next window,
  // a checkpoint or the finish comes).
  const bool implicit = context.scene.coupling.is_implicit();
  std::string window_start;
  WindowResult start_result;  // the previous window's report, at the start of the one iterated
  bool output_pending = false;
  while (true) {
    const Window window = participant.next_window();
    if (window.rolled_back) {
      // Interrupted mid-window: the state after window `index` is the start of the window being
      // iterated. Its iterations are dropped (their output frame too); the run stops next.
      solver.load_checkpoint(checkpoint::Reader(
          window_start, fmt::format("the start of window {} (in memory)", window.index + 1),
          context.program));
      output_pending = false;
      write_checkpoint(context, solver, clock, window, start_result,
                       participant.previous_window_fields());
      continue;
    }
    if (output_pending && (window.checkpoint || window.finish || window.iteration == 0)) {
      solver.window_accepted();
      write_if_due();
      output_pending = false;
    }
    if (window.checkpoint) {
      write_checkpoint(context, solver, clock, window, last, participant.published_fields());
      continue;
    }
    context.maybe_inject_fault(window.index);
    if (window.finish) {
      if (interval > 0.0 && !clock.written_at(solver.output_time())) solver.write_output();
      MetricsReport report;
      solver.finish(report);
      participant.finished(report.dump());
      return;
    }
    if (restored && window.index == restored->window) {
      // The restart window: window N's fields again, nothing computed (its frame, if one was
      // due, is in the run that wrote the checkpoint).
      for (const auto& [name, values] : restored->fields) participant.publish(name, values);
      last = {0, restored->stable_dt};
      restored->fields.clear();
    } else if (implicit && window.index >= 1) {
      if (window.iteration == 0) {
        checkpoint::Writer start(context.program);
        solver.save_checkpoint(start);
        window_start = start.encode();
        start_result = last;
      } else {
        solver.load_checkpoint(checkpoint::Reader(
            window_start, fmt::format("the start of window {} (in memory)", window.index),
            context.program));
      }
      last = solver.advance(window);
      output_pending = true;
    } else {
      last = window.index == 0 ? solver.initial_window(window) : solver.advance(window);
      if (window.index > 0) solver.window_accepted();
      write_if_due();
    }
    participant.done(last.steps, last.stable_dt);
  }
}

}  // namespace cosim::coupler
