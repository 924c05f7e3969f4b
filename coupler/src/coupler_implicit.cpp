// The coupler's window loop of the implicit schemes (serial-implicit, parallel-implicit).
//
// Window k is a fixed-point problem x = H(x) in the fields the solids hand the flow (positions,
// velocities, drag of every solid; in the parallel scheme also the flow's velocity samples at
// every solid). Iteration 0 is the explicit scheme's window (its inputs are window k-1's
// accepted fields); after iteration i the coupler measures H(x_i) - x_i, and unless it has
// converged it computes x_{i+1} with the accelerator, publishes it as its own fields of
// (k, i + 1) and grants that iteration; every participant rolls back to its state at the start
// of window k first (run_solver_loop). The coupler only post-processes exchanged fields here
// (an exchange rule); the physics stays in the participants.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "cosim/coupler/acceleration.hpp"
#include "cosim/coupler/coupler.hpp"
#include "cosim/coupler/exchange.hpp"
#include "cosim/coupler/implicit.hpp"
#include "steady_clock.hpp"

namespace cosim::coupler {

namespace {
using cosim_msgs::status_t;
using cosim_msgs::window_t;

AccelerationOptions acceleration_options(const scenario::ImplicitSettings& settings) {
  AccelerationOptions options;
  switch (settings.acceleration) {
    case scenario::Acceleration::none:
      options.kind = AccelerationKind::none;
      break;
    case scenario::Acceleration::constant:
      options.kind = AccelerationKind::constant;
      break;
    case scenario::Acceleration::aitken:
      options.kind = AccelerationKind::aitken;
      break;
    case scenario::Acceleration::iqn_ils:
      options.kind = AccelerationKind::iqn_ils;
      break;
  }
  options.relaxation = settings.relaxation;
  options.reuse_windows = settings.reuse_windows;
  options.filter = settings.filter;
  options.max_step = settings.max_step;
  return options;
}
}  // namespace

double Coupler::run_implicit_windows(ProcessGroup& processes, RunResult& result) {
  const auto& settings = scene_.coupling.implicit;
  const bool serial = scene_.coupling.is_serial();
  const double resend = scene_.coupling.resend_interval;
  Accelerator accelerator(acceleration_options(settings));
  result.acceleration = acceleration_name(accelerator.options().kind);

  const auto* flow = scene_.flow();
  std::vector<std::string> solids;
  for (const auto* solid : scene_.solids()) solids.push_back(solid->acts_as);

  double next_time = start_plan();
  const int64_t first = static_cast<int64_t>(plan_.size()) - 1;
  std::map<int64_t, double> stable_dt;  // smallest stable dt of each window's accepted iteration
  std::map<int64_t, int32_t> accepted{{first - 1, 0}};
  Clock::time_point window_one_started{};

  // Every iteration's report counts its steps; only iteration 0 counts a window.
  auto accept = [&](const status_t& status) {
    book_report(status, status.header.iteration == 0, stable_dt);
  };

  // One iteration of one window, granted until every participant's DONE is in.
  auto run_iteration = [&](int64_t index, int32_t iteration) {
    const auto [time, dt] = plan_[index];
    stable_dt.erase(index);
    Collection collection;
    collection.stamp = Stamp{index, time, dt, iteration};
    collection.command = window_t::COMMAND_ADVANCE;
    collection.answer = status_t::STATE_DONE;
    collection.during = window_text(index) + fmt::format(", iteration {}", iteration);
    collection.failed_during = "in " + collection.during;
    collection.accept = accept;
    // Stopped from outside mid-window: every participant rolls back to the start of this window
    // and saves it, the state after the last accepted window (run_solver_loop).
    collection.on_interrupt = [&, index] {
      const int64_t last_accepted = index - 1;
      if (last_accepted <= first) return;
      book_.request(last_accepted, end_of(last_accepted));
      await_checkpoints(processes, last_accepted, true);
      if (book_.complete(last_accepted)) result.windows_completed = last_accepted;
    };
    const int32_t previous = accepted.contains(index - 1) ? accepted[index - 1] : 0;
    collection.broadcast = [&, index, iteration, previous, time = time, dt = dt] {
      bus_->publish_window(Stamp{index, time, dt, iteration}, window_t::COMMAND_ADVANCE,
                           result.total_windows, "", {{time, dt}}, book_.pending(index - 1),
                           previous);
    };
    collect(processes, collection);
  };

  // A field of (index, iteration) heard from `sender`, asking again until it comes.
  auto field = [&](const std::string& sender, const std::string& name, int64_t index,
                   int32_t iteration) {
    const FieldKey key{sender, index, name, iteration};
    const auto start = Clock::now();
    auto last_request = start;
    while (true) {
      if (auto values = bus_->field_values(key)) return std::move(*values);
      if (seconds_since(start) > scene_.coupling.timeout) {
        throw Failure(
            fmt::format("'{}' did not deliver its field '{}' of {}, iteration {}, "
                        "within {:.1f} s",
                        sender, name, window_text(index), iteration, scene_.coupling.timeout));
      }
      if (seconds_since(last_request) >= resend) {
        bus_->request_field(key);
        last_request = Clock::now();
      }
      bus_->poll(resend);
    }
  };

  // The iterated fields, in a fixed order: per solid its positions [m], velocities [m/s] and
  // drag [N]; in the parallel scheme the flow's velocity samples at it [m/s].
  std::vector<FieldBlock> blocks;
  for (const auto& solid : solids) {
    for (const char* name : {exchange::kPositions, exchange::kVelocities, exchange::kDrag}) {
      FieldBlock block;
      block.sender = solid;
      block.field = name;
      block.input = exchange::solid_field_for_flow(name, solid);
      block.absolute = name == std::string(exchange::kPositions)    ? settings.absolute_position
                       : name == std::string(exchange::kVelocities) ? settings.absolute_velocity
                                                                    : settings.absolute_force;
      blocks.push_back(block);
    }
    if (flow && !serial) {
      FieldBlock block;
      block.sender = flow->acts_as;
      block.field = exchange::ambient_velocity_field(solid);
      block.input = block.field;
      block.absolute = settings.absolute_velocity;
      blocks.push_back(block);
    }
  }
  // The fields of (index, iteration) as one vector; `drag_scale` multiplies the drag blocks
  // (iteration 0 takes window k-1's drag as the flow does: rescaled by dt_{k-1} / dt_k).
  auto gather = [&](int64_t index, int32_t iteration, double drag_scale) {
    std::vector<std::vector<double>> parts;
    Eigen::Index total = 0;
    for (auto& block : blocks) {
      parts.push_back(field(block.sender, block.field, index, iteration));
      block.offset = total;
      block.size = static_cast<Eigen::Index>(parts.back().size());
      total += block.size;
    }
    Eigen::VectorXd vector(total);
    for (std::size_t b = 0; b < blocks.size(); ++b) {
      const double scale = blocks[b].field == exchange::kDrag ? drag_scale : 1.0;
      for (Eigen::Index j = 0; j < blocks[b].size; ++j) {
        vector(blocks[b].offset + j) = scale * parts[b][static_cast<std::size_t>(j)];
      }
    }
    return vector;
  };
  // What the next iteration reads from the coupler: the accelerated input, and the fields it
  // passes on as they are (displaced volumes; in the parallel scheme water fraction and surface).
  auto publish_input = [&](int64_t index, int32_t iteration, const Eigen::VectorXd& x,
                           int32_t answered) {
    const auto [time, dt] = plan_[index];
    const Stamp stamp{index, time, dt, iteration};
    for (const auto& block : blocks) {
      bus_->publish_field(
          stamp, block.input,
          std::span<const double>(x.data() + block.offset, static_cast<std::size_t>(block.size)));
    }
    for (const auto& solid : solids) {
      if (exchange::displaces_water(solid)) {
        const auto volumes = field(solid, exchange::kVolumes, index, answered);
        bus_->publish_field(stamp, exchange::solid_field_for_flow(exchange::kVolumes, solid),
                            volumes);
      }
      if (flow && !serial) {
        for (const auto& name :
             {exchange::water_fraction_field(solid), exchange::surface_field(solid)}) {
          bus_->publish_field(stamp, name, field(flow->acts_as, name, index, answered));
        }
      }
    }
  };

  // Length of the window before: a restart continues after a window of the nominal length (an
  // adaptive restart's first measure may then cost one iteration more, never a wrong result).
  double previous_dt = options_.restart ? scene_.coupling.window : 0.0;
  int64_t completed = first - 1;
  // Window 0 (or the restart window): the initial exchange, not iterated.
  run_iteration(first, 0);
  accepted[first] = 0;
  completed = first;
  window_one_started = Clock::now();
  while (plan_next_window(next_time, stable_dt, result)) {
    const auto index = static_cast<int64_t>(plan_.size()) - 1;
    const double dt = plan_.back().second;

    // The flow's first iteration takes window k-1's drag rescaled to window k's length (the
    // window after window 0 takes none: window 0 has no length).
    const double drag_scale = previous_dt > 0.0 ? previous_dt / dt : 0.0;
    Eigen::VectorXd x = gather(index - 1, accepted[index - 1], drag_scale);
    int32_t iteration = 0;
    Eigen::VectorXd scales;
    while (true) {
      run_iteration(index, iteration);
      const Eigen::VectorXd h = gather(index, iteration, 1.0);
      if (h.size() != x.size()) {
        throw Failure(fmt::format("the exchanged fields of {} changed size between iterations",
                                  window_text(index)));
      }
      const auto measure = measure_convergence(blocks, x, h, settings.relative_tolerance);
      if (measure.converged) break;
      if (iteration + 1 >= settings.max_iterations) {
        ++result.windows_at_max_iterations;
        const std::string text = fmt::format(
            "{} did not converge in {} coupling iterations ({} is {:.3g} times its tolerance)",
            window_text(index), settings.max_iterations, measure.worst_field, measure.worst);
        if (settings.at_max_iterations == scenario::AtMaxIterations::stop) {
          throw Failure(text + " (coupling.implicit.at_max_iterations: stop)");
        }
        if (settings.max_iterations > 1) spdlog::warn("{}; continuing", text);
        break;
      }
      // One scale per window (from its first answer), so the accelerator's columns of one
      // window are differences in the same units.
      if (iteration == 0) scales = block_scales(blocks, h);
      const Eigen::VectorXd next =
          accelerator.next(x.cwiseQuotient(scales), h.cwiseQuotient(scales)).cwiseProduct(scales);
      if (!next.allFinite()) {
        throw Failure(fmt::format("the coupling iteration of {} diverged (iteration {}: {})",
                                  window_text(index), iteration, measure.worst_field));
      }
      x = next;
      publish_input(index, iteration + 1, x, iteration);
      ++iteration;
    }
    accelerator.end_window();
    accepted[index] = iteration;
    result.iterations.push_back(iteration + 1);
    completed = index;
    result.windows_completed = completed;
    previous_dt = dt;
    bus_->forget_fields_before(index - 2);
  }
  if (accelerator.bounded_steps() > 0) {
    spdlog::info("coupling.implicit.max_step shortened {} accelerated updates",
                 accelerator.bounded_steps());
  }
  await_checkpoints(processes, completed, false);
  book_overhead(result, window_one_started, completed, serial);
  return next_time;
}

}  // namespace cosim::coupler
