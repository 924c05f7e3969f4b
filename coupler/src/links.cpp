#include "cosim/coupler/links.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>

namespace cosim::coupler {

SolidLink::SolidLink(Participant& participant, const scenario::Scene& scene,
                     std::size_t point_count)
    : participant_(participant),
      serial_(scene.coupling.is_serial()),
      implicit_(scene.coupling.is_implicit()),
      resolved_(
          exchange::resolved_by_flow(scene.coupling.interface.resolved_plants, participant.name())),
      point_count_(point_count) {
  if (const auto* flow = scene.flow()) flow_name_ = flow->acts_as;
}

void SolidLink::publish_state(std::span<const Eigen::Vector3d> positions,
                              std::span<const Eigen::Vector3d> velocities,
                              std::span<const Eigen::Vector3d> drag,
                              std::span<const double> volumes) {
  participant_.publish(exchange::kPositions, exchange::pack(positions));
  participant_.publish(exchange::kVelocities, exchange::pack(velocities));
  participant_.publish(exchange::kDrag, exchange::pack(drag));
  if (!volumes.empty() && volumes.size() != positions.size()) {
    throw CouplingError(fmt::format("field '{}' of '{}': {} volumes for {} points",
                                    exchange::kVolumes, participant_.name(), volumes.size(),
                                    positions.size()));
  }
  if (!volumes.empty() || exchange::displaces_water(participant_.name())) {
    participant_.publish(exchange::kVolumes, std::vector<double>(volumes.begin(), volumes.end()));
  }
}

void SolidLink::publish_window_state(std::span<const Eigen::Vector3d> start, double dt,
                                     std::span<const Eigen::Vector3d> positions,
                                     std::span<const Eigen::Vector3d> velocities,
                                     std::span<const Eigen::Vector3d> drag,
                                     std::span<const double> volumes) {
  if (!resolved_ || !implicit_) {
    publish_state(positions, velocities, drag, volumes);
    return;
  }
  if (start.size() != positions.size()) {
    throw CouplingError(fmt::format("'{}': {} window-start positions for {} points",
                                    participant_.name(), start.size(), positions.size()));
  }
  std::vector<Eigen::Vector3d> mean(positions.size());
  for (std::size_t i = 0; i < positions.size(); ++i) {
    mean[i] = exchange::resolved_velocity(start[i], positions[i], velocities[i], dt);
  }
  publish_state(positions, mean, drag, volumes);
}

AmbientFlow SolidLink::receive(const std::string& sender, int64_t flow_window, int32_t iteration) {
  const auto key = std::tuple(sender, flow_window, iteration);
  if (const auto cached = cache_.find(key); cached != cache_.end()) return cached->second;
  AmbientFlow flow;
  const std::string me = participant_.name();
  const std::string velocity_field = exchange::ambient_velocity_field(me);
  const std::string water_field = exchange::water_fraction_field(me);
  flow.velocity = exchange::unpack(
      participant_.receive(sender, velocity_field, flow_window, iteration), point_count_,
      fmt::format("field '{}' from '{}' (window {})", velocity_field, sender, flow_window));
  flow.water_fraction = participant_.receive(sender, water_field, flow_window, iteration);
  if (flow.water_fraction.size() != point_count_) {
    throw CouplingError(fmt::format("field '{}' from '{}' (window {}): expected {} values, got {}",
                                    water_field, sender, flow_window, point_count_,
                                    flow.water_fraction.size()));
  }
  flow.surface_elevation =
      participant_.receive(sender, exchange::surface_field(me), flow_window, iteration);
  if (flow.surface_elevation.size() != point_count_) {
    throw CouplingError(fmt::format("field '{}' from '{}' (window {}): expected {} values, got {}",
                                    exchange::surface_field(me), sender, flow_window, point_count_,
                                    flow.surface_elevation.size()));
  }
  if (resolved_) {
    const std::string load_field = exchange::fluid_load_field(me);
    flow.fluid_load = exchange::unpack(
        participant_.receive(sender, load_field, flow_window, iteration), point_count_,
        fmt::format("field '{}' from '{}' (window {})", load_field, sender, flow_window));
  }
  std::erase_if(cache_,
                [&](const auto& item) { return std::get<1>(item.first) < flow_window - 1; });
  cache_[key] = flow;
  return flow;
}

std::pair<AmbientFlow, AmbientFlow> SolidLink::ambient(const Window& window) {
  if (flow_name_.empty()) {
    AmbientFlow still{std::vector<Eigen::Vector3d>(point_count_, Eigen::Vector3d::Zero()),
                      std::vector<double>(point_count_, 0.0),
                      std::vector<double>(point_count_, -std::numeric_limits<double>::infinity()),
                      {}};
    return {still, still};
  }
  const auto windows = exchange::flow_windows_for_solid(window.index, serial_);
  if (implicit_) {
    AmbientFlow begin = receive(flow_name_, windows.begin, window.accepted_iteration);
    if (serial_) return {begin, receive(flow_name_, window.index, window.iteration)};
    if (window.iteration == 0) return {begin, begin};
    return {begin, receive(exchange::kCoupler, window.index, window.iteration)};
  }
  AmbientFlow begin = receive(flow_name_, windows.begin);
  AmbientFlow end = windows.end == windows.begin ? begin : receive(flow_name_, windows.end);
  return {std::move(begin), std::move(end)};
}

FlowLink::FlowLink(Participant& participant, const scenario::Scene& scene, SolverFrame frame)
    : participant_(participant),
      frame_(frame),
      implicit_(scene.coupling.is_implicit()),
      resolved_plants_(scene.coupling.interface.resolved_plants) {
  for (const auto* solid : scene.solids()) solids_.push_back(solid->acts_as);
}

std::vector<SolidForcing> FlowLink::receive_solids(const Window& window, bool with_volumes) {
  // Implicit iterations after the first take the coupler's relaxed fields of this window itself.
  const bool relaxed = implicit_ && window.iteration > 0;
  const int64_t solid_window =
      relaxed ? window.index : exchange::solid_window_for_flow(window.index);
  const int32_t iteration = relaxed ? window.iteration : implicit_ ? window.accepted_iteration : 0;
  // The drag of window k-1 acted on the solids for dt_{k-1}; spread over dt_k it gives the flow
  // the same impulse (adaptive windows change length). The relaxed drag is of window k already.
  const double impulse_scale = relaxed ? 1.0 : window.dt > 0.0 ? previous_dt_ / window.dt : 0.0;
  if (window.dt > 0.0) previous_dt_ = window.dt;
  std::vector<SolidForcing> states;
  for (const auto& name : solids_) {
    const std::string sender = relaxed ? exchange::kCoupler : name;
    auto field = [&](const char* what) {
      return relaxed ? exchange::solid_field_for_flow(what, name) : std::string(what);
    };
    auto what = [&](const char* field_name) {
      return fmt::format("field '{}' from '{}' (window {})", field(field_name), sender,
                         solid_window);
    };
    auto get = [&](const char* field_name) {
      return participant_.receive(sender, field(field_name), solid_window, iteration);
    };
    const auto positions = exchange::unpack(get(exchange::kPositions), what(exchange::kPositions));
    const std::size_t count = positions.size();
    const auto velocities =
        exchange::unpack(get(exchange::kVelocities), count, what(exchange::kVelocities));
    const auto drag = exchange::unpack(get(exchange::kDrag), count, what(exchange::kDrag));
    std::vector<double> volumes(count, 0.0);
    if (with_volumes && exchange::displaces_water(name)) volumes = get(exchange::kVolumes);
    if (volumes.size() != count) {
      throw CouplingError(fmt::format("{}: expected {} values, got {}", what(exchange::kVolumes),
                                      count, volumes.size()));
    }
    SolidForcing state;
    state.name = name;
    if (resolves(name)) {
      // Explicit, iteration 0: positions and velocities are the window-start state. Later
      // iterations: they are the iterate's end; the start is the accepted window-start
      // positions, as iteration 0 read them (exchange::resolved_path; the velocities then unused).
      std::vector<Eigen::Vector3d> start = positions;
      if (relaxed) {
        const int64_t previous = exchange::solid_window_for_flow(window.index);
        start = exchange::unpack(
            participant_.receive(name, exchange::kPositions, previous, window.accepted_iteration),
            count,
            fmt::format("field '{}' from '{}' (window {})", exchange::kPositions, name, previous));
      }
      for (std::size_t i = 0; i < count; ++i) {
        const auto path = exchange::resolved_path(start[i], velocities[i],
                                                  relaxed ? &positions[i] : nullptr, window.dt);
        state.path_start.push_back(frame_.to_solver(path.start));
        state.path_velocity.push_back(frame_.to_solver(path.velocity));
      }
    }
    // 2D: the slice of the span the flow stands for holds volume / span of each solid.
    for (const double v : volumes) state.volumes.push_back(v / frame_.span());  // 3D: span 1
    state.positions.reserve(count);
    state.velocities.reserve(count);
    state.reaction.reserve(count);
    for (std::size_t i = 0; i < count; ++i) {
      state.positions.push_back(frame_.to_solver(positions[i]));
      state.velocities.push_back(frame_.to_solver(velocities[i]));
      const Eigen::Vector3d reaction = -impulse_scale * drag[i];  // world [N]
      state.reaction.push_back(frame_.force_to_solver(reaction));
      booked_impulse_ += (reaction - frame_.out_of_plane(reaction)) * window.dt;
      out_of_plane_impulse_ += frame_.out_of_plane(reaction) * window.dt;
    }
    states.push_back(std::move(state));
  }
  return states;
}

void FlowLink::publish_samples(const std::string& solid,
                               std::span<const Eigen::Vector3d> ambient_velocity,
                               std::span<const double> water_fraction,
                               std::span<const double> surface_elevation) {
  std::vector<Eigen::Vector3d> world(ambient_velocity.size());
  for (std::size_t i = 0; i < world.size(); ++i) world[i] = frame_.to_world(ambient_velocity[i]);
  participant_.publish(exchange::ambient_velocity_field(solid), exchange::pack(world));
  participant_.publish(exchange::water_fraction_field(solid),
                       std::vector<double>(water_fraction.begin(), water_fraction.end()));
  std::vector<double> surface(surface_elevation.begin(), surface_elevation.end());
  if (surface.empty()) surface.assign(water_fraction.size(), std::nan(""));
  participant_.publish(exchange::surface_field(solid), surface);
}

void FlowLink::publish_fluid_load(const std::string& solid, std::span<const Eigen::Vector3d> load) {
  std::vector<Eigen::Vector3d> world(load.size());
  for (std::size_t i = 0; i < world.size(); ++i) world[i] = frame_.force_to_world(load[i]);
  participant_.publish(exchange::fluid_load_field(solid), exchange::pack(world));
}

void FlowLink::save_checkpoint(checkpoint::Writer& out) const {
  out.value("flow_link.previous_dt", previous_dt_);
  out.value("flow_link.booked_impulse", booked_impulse_);
  out.value("flow_link.out_of_plane_impulse", out_of_plane_impulse_);
}

void FlowLink::load_checkpoint(const checkpoint::Reader& in) {
  previous_dt_ = in.value<double>("flow_link.previous_dt");
  booked_impulse_ = in.value<Eigen::Vector3d>("flow_link.booked_impulse");
  out_of_plane_impulse_ = in.value<Eigen::Vector3d>("flow_link.out_of_plane_impulse");
}

}  // namespace cosim::coupler
