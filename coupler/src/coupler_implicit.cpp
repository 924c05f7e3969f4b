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
  options.positive_aitken = settings.positive_aitken;
  return options;
}
}  // namespace

// The implicit loop's state, and its stages as functions: granting one iteration, reading a
// field, gathering the iterated vector, publishing the next input, iterating one window.
class Coupler::ImplicitWindows {
 public:
  ImplicitWindows(Coupler& coupler, ProcessGroup& processes, RunResult& result)
      : c_(coupler),
        processes_(processes),
        result_(result),
        settings_(coupler.scene_.coupling.implicit),
        serial_(coupler.scene_.coupling.is_serial()),
        accelerator_(acceleration_options(settings_)),
        flow_(coupler.scene_.flow()),
        resolved_plants_(coupler.scene_.coupling.interface.resolved_plants) {
    result_.acceleration = acceleration_name(accelerator_.options().kind);
    for (const auto* solid : c_.scene_.solids()) solids_.push_back(solid->acts_as);
    blocks_ = iterated_blocks();
    for (const auto& block : blocks_) {
      result_.convergence_fields.push_back(block.field + " of " + block.sender);
    }
  }

  // Window 0 (or the restart window) is the initial exchange, not iterated; every later window
  // is iterated to convergence. Returns the simulated time reached.
  double run() {
    double next_time = c_.start_plan();
    first_ = static_cast<int64_t>(c_.plan_.size()) - 1;
    accepted_[first_ - 1] = 0;
    // Length of the window before: a restart continues after a window of the nominal length
    // (an adaptive restart's first measure may then cost one iteration more, never a wrong
    // result).
    double previous_dt = c_.options_.restart ? c_.scene_.coupling.window : 0.0;
    run_iteration(first_, 0);
    accepted_[first_] = 0;
    int64_t completed = first_;
    const Clock::time_point window_one_started = Clock::now();
    while (c_.plan_next_window(next_time, stable_dt_, result_)) {
      const auto index = static_cast<int64_t>(c_.plan_.size()) - 1;
      const double dt = c_.plan_.back().second;
      // The flow's first iteration takes window k-1's drag rescaled to window k's length (the
      // window after window 0 takes none: window 0 has no length).
      const double drag_scale = previous_dt > 0.0 ? previous_dt / dt : 0.0;
      const int32_t iteration =
          iterate_window(index, gather(index - 1, accepted_[index - 1], drag_scale));
      accelerator_.end_window();
      accepted_[index] = iteration;
      result_.iterations.push_back(iteration + 1);
      completed = index;
      result_.windows_completed = completed;
      previous_dt = dt;
      c_.bus_->forget_fields_before(index - 2);
    }
    result_.aitken_restarts = accelerator_.aitken_restarts();
    if (accelerator_.bounded_steps() > 0) {
      spdlog::info("coupling.implicit.max_step shortened {} accelerated updates",
                   accelerator_.bounded_steps());
    }
    c_.await_checkpoints(processes_, completed, false);
    c_.book_overhead(result_, window_one_started, completed, serial_);
    return next_time;
  }

 private:
  // Iterates window `index` from the input x until the fields converge or the limit is
  // reached; returns the accepted iteration.
  int32_t iterate_window(int64_t index, Eigen::VectorXd x) {
    Eigen::VectorXd scales;
    for (int32_t iteration = 0;; ++iteration) {
      run_iteration(index, iteration);
      const Eigen::VectorXd h = gather(index, iteration, 1.0);
      if (h.size() != x.size()) {
        throw Failure(fmt::format("the exchanged fields of {} changed size between iterations",
                                  c_.window_text(index)));
      }
      const auto measure = measure_convergence(blocks_, x, h, settings_.relative_tolerance);
      result_.convergence.push_back({index, c_.plan_[index].first, iteration, measure.ratios});
      if (measure.converged) return iteration;
      if (iteration + 1 >= settings_.max_iterations) {
        ++result_.windows_at_max_iterations;
        const std::string text = fmt::format(
            "{} did not converge in {} coupling iterations ({} is {:.3g} times its tolerance)",
            c_.window_text(index), settings_.max_iterations, measure.worst_field, measure.worst);
        if (settings_.at_max_iterations == scenario::AtMaxIterations::stop) {
          throw Failure(text + " (coupling.implicit.at_max_iterations: stop)");
        }
        if (settings_.max_iterations > 1) spdlog::warn("{}; continuing", text);
        return iteration;
      }
      // One scale per window (from its first answer), so the accelerator's columns of one
      // window are differences in the same units.
      if (iteration == 0) scales = block_scales(blocks_, h);
      const Eigen::VectorXd next = accelerate(x, h, scales);
      if (!next.allFinite()) {
        throw Failure(fmt::format("the coupling iteration of {} diverged (iteration {}: {})",
                                  c_.window_text(index), iteration, measure.worst_field));
      }
      x = next;
      publish_input(index, iteration + 1, x, iteration);
    }
  }

  // The next input: the accelerated blocks from the accelerator (in the scaled units), the
  // others as the senders answered.
  Eigen::VectorXd accelerate(const Eigen::VectorXd& x, const Eigen::VectorXd& h,
                             const Eigen::VectorXd& scales) {
    const auto entries = accelerated_entries(blocks_);
    const auto count = static_cast<Eigen::Index>(entries.size());
    Eigen::VectorXd xa(count), ha(count), sa(count);
    for (Eigen::Index j = 0; j < count; ++j) {
      const auto e = entries[static_cast<std::size_t>(j)];
      xa(j) = x(e);
      ha(j) = h(e);
      sa(j) = scales(e);
    }
    const Eigen::VectorXd na =
        accelerator_.next(xa.cwiseQuotient(sa), ha.cwiseQuotient(sa)).cwiseProduct(sa);
    Eigen::VectorXd next = h;
    for (Eigen::Index j = 0; j < count; ++j) next(entries[static_cast<std::size_t>(j)]) = na(j);
    return next;
  }

  // One iteration of one window, granted until every participant's DONE is in.
  void run_iteration(int64_t index, int32_t iteration) {
    const auto [time, dt] = c_.plan_[index];
    stable_dt_.erase(index);
    Collection collection;
    collection.stamp = Stamp{index, time, dt, iteration};
    collection.command = window_t::COMMAND_ADVANCE;
    collection.answer = status_t::STATE_DONE;
    collection.during = c_.window_text(index) + fmt::format(", iteration {}", iteration);
    collection.failed_during = "in " + collection.during;
    // Every iteration's report counts its steps; only iteration 0 counts a window.
    collection.accept = [this](const status_t& status) {
      c_.book_report(status, status.header.iteration == 0, stable_dt_);
    };
    // Stopped from outside mid-window: every participant rolls back to the start of this window
    // and saves it, the state after the last accepted window (run_solver_loop).
    collection.on_interrupt = [this, index] {
      const int64_t last_accepted = index - 1;
      if (last_accepted <= first_) return;
      c_.book_.request(last_accepted, c_.end_of(last_accepted));
      c_.await_checkpoints(processes_, last_accepted, true);
      if (c_.book_.complete(last_accepted)) result_.windows_completed = last_accepted;
    };
    const int32_t previous = accepted_.contains(index - 1) ? accepted_[index - 1] : 0;
    collection.broadcast = [this, index, iteration, previous, time = time, dt = dt] {
      c_.bus_->publish_window(Stamp{index, time, dt, iteration}, window_t::COMMAND_ADVANCE,
                              result_.total_windows, "", {{time, dt}}, c_.book_.pending(index - 1),
                              previous);
    };
    c_.collect(processes_, collection);
  }

  // A field of (index, iteration) heard from `sender`, asking again until it comes.
  std::vector<double> field(const std::string& sender, const std::string& name, int64_t index,
                            int32_t iteration) {
    const FieldKey key{sender, index, name, iteration};
    const double resend = c_.scene_.coupling.resend_interval;
    const auto start = Clock::now();
    auto last_request = start;
    while (true) {
      if (auto values = c_.bus_->field_values(key)) return std::move(*values);
      if (seconds_since(start) > c_.scene_.coupling.timeout) {
        throw Failure(fmt::format(
            "'{}' did not deliver its field '{}' of {}, iteration {}, within {:.1f} s", sender,
            name, c_.window_text(index), iteration, c_.scene_.coupling.timeout));
      }
      if (seconds_since(last_request) >= resend) {
        c_.bus_->request_field(key);
        last_request = Clock::now();
      }
      c_.bus_->poll(resend);
    }
  }

  // The iterated fields, in a fixed order: per solid its positions [m], velocities [m/s] and
  // drag [N]; in the parallel scheme the flow's velocity samples at it [m/s].
  std::vector<FieldBlock> iterated_blocks() const {
    std::vector<FieldBlock> blocks;
    for (const auto& solid : solids_) {
      for (const char* name : {exchange::kPositions, exchange::kVelocities, exchange::kDrag}) {
        FieldBlock block;
        block.sender = solid;
        block.field = name;
        block.input = exchange::solid_field_for_flow(name, solid);
        // A solid the flow resolves is read there by its positions alone (the wall's path).
        block.accelerated = !exchange::resolved_by_flow(resolved_plants_, solid) ||
                            name == std::string(exchange::kPositions);
        block.absolute = name == std::string(exchange::kPositions)    ? settings_.absolute_position
                         : name == std::string(exchange::kVelocities) ? settings_.absolute_velocity
                                                                      : settings_.absolute_force;
        blocks.push_back(block);
      }
      if (flow_ && !serial_) {
        FieldBlock block;
        block.sender = flow_->acts_as;
        block.field = exchange::ambient_velocity_field(solid);
        block.input = block.field;
        block.absolute = settings_.absolute_velocity;
        blocks.push_back(block);
      }
    }
    return blocks;
  }

  // The fields of (index, iteration) as one vector; `drag_scale` multiplies the drag blocks
  // (iteration 0 takes window k-1's drag as the flow does: rescaled by dt_{k-1} / dt_k).
  Eigen::VectorXd gather(int64_t index, int32_t iteration, double drag_scale) {
    std::vector<std::vector<double>> parts;
    Eigen::Index total = 0;
    for (auto& block : blocks_) {
      parts.push_back(field(block.sender, block.field, index, iteration));
      block.offset = total;
      block.size = static_cast<Eigen::Index>(parts.back().size());
      total += block.size;
    }
    Eigen::VectorXd vector(total);
    for (std::size_t b = 0; b < blocks_.size(); ++b) {
      const double scale = blocks_[b].field == exchange::kDrag ? drag_scale : 1.0;
      for (Eigen::Index j = 0; j < blocks_[b].size; ++j) {
        vector(blocks_[b].offset + j) = scale * parts[b][static_cast<std::size_t>(j)];
      }
    }
    return vector;
  }

  // What the next iteration reads from the coupler: the accelerated input, and the fields it
  // passes on as they are (displaced volumes; in the parallel scheme water fraction and
  // surface).
  void publish_input(int64_t index, int32_t iteration, const Eigen::VectorXd& x, int32_t answered) {
    const auto [time, dt] = c_.plan_[index];
    const Stamp stamp{index, time, dt, iteration};
    for (const auto& block : blocks_) {
      c_.bus_->publish_field(
          stamp, block.input,
          std::span<const double>(x.data() + block.offset, static_cast<std::size_t>(block.size)));
    }
    for (const auto& solid : solids_) {
      if (exchange::displaces_water(solid)) {
        const auto volumes = field(solid, exchange::kVolumes, index, answered);
        c_.bus_->publish_field(stamp, exchange::solid_field_for_flow(exchange::kVolumes, solid),
                               volumes);
      }
      if (flow_ && !serial_) {
        for (const auto& name :
             {exchange::water_fraction_field(solid), exchange::surface_field(solid)}) {
          c_.bus_->publish_field(stamp, name, field(flow_->acts_as, name, index, answered));
        }
      }
    }
  }

  Coupler& c_;
  ProcessGroup& processes_;
  RunResult& result_;
  const scenario::ImplicitSettings& settings_;
  const bool serial_;
  Accelerator accelerator_;
  const scenario::ParticipantEntry* flow_;
  const bool resolved_plants_;
  std::vector<std::string> solids_;
  std::vector<FieldBlock> blocks_;
  int64_t first_ = 0;
  std::map<int64_t, double> stable_dt_;  // smallest stable dt of each window's accepted iteration
  std::map<int64_t, int32_t> accepted_;  // the accepted iteration of each window
};

double Coupler::run_implicit_windows(ProcessGroup& processes, RunResult& result) {
  return ImplicitWindows(*this, processes, result).run();
}

}  // namespace cosim::coupler
