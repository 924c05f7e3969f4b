#include "cosim/coupler/links.hpp"

#include <fmt/format.h>

namespace cosim::coupler {

SolidLink::SolidLink(Participant& participant, const scenario::Scene& scene,
                     std::size_t point_count)
    : participant_(participant),
      serial_(scene.coupling.scheme == "serial-explicit"),
      point_count_(point_count) {
  if (const auto* flow = scene.flow()) flow_name_ = flow->acts_as;
}

void SolidLink::publish_state(std::span<const Eigen::Vector3d> positions,
                              std::span<const Eigen::Vector3d> velocities,
                              std::span<const Eigen::Vector3d> drag) {
  participant_.publish(exchange::kPositions, exchange::pack(positions));
  participant_.publish(exchange::kVelocities, exchange::pack(velocities));
  participant_.publish(exchange::kDrag, exchange::pack(drag));
}

AmbientFlow SolidLink::receive(int64_t flow_window) {
  if (const auto cached = cache_.find(flow_window); cached != cache_.end()) return cached->second;
  AmbientFlow flow;
  const std::string me = participant_.name();
  const std::string velocity_field = exchange::ambient_velocity_field(me);
  const std::string water_field = exchange::water_fraction_field(me);
  flow.velocity = exchange::unpack(
      participant_.receive(flow_name_, velocity_field, flow_window), point_count_,
      fmt::format("field '{}' from '{}' (window {})", velocity_field, flow_name_, flow_window));
  flow.water_fraction = participant_.receive(flow_name_, water_field, flow_window);
  if (flow.water_fraction.size() != point_count_) {
    throw CouplingError(fmt::format("field '{}' from '{}' (window {}): expected {} values, got {}",
                                    water_field, flow_name_, flow_window, point_count_,
                                    flow.water_fraction.size()));
  }
  std::erase_if(cache_, [&](const auto& item) { return item.first < flow_window - 1; });
  cache_[flow_window] = flow;
  return flow;
}

std::pair<AmbientFlow, AmbientFlow> SolidLink::ambient(const Window& window) {
  if (flow_name_.empty()) {
    AmbientFlow still{std::vector<Eigen::Vector3d>(point_count_, Eigen::Vector3d::Zero()),
                      std::vector<double>(point_count_, 0.0)};
    return {still, still};
  }
  const auto windows = exchange::flow_windows_for_solid(window.index, serial_);
  AmbientFlow begin = receive(windows.begin);
  AmbientFlow end = windows.end == windows.begin ? begin : receive(windows.end);
  return {std::move(begin), std::move(end)};
}

FlowLink::FlowLink(Participant& participant, const scenario::Scene& scene)
    : participant_(participant) {
  for (const auto* solid : scene.solids()) solids_.push_back(solid->acts_as);
}

std::vector<SolidState> FlowLink::receive_solids(const Window& window) {
  const int64_t solid_window = exchange::solid_window_for_flow(window.index);
  std::vector<SolidState> states;
  for (const auto& name : solids_) {
    SolidState state;
    state.name = name;
    auto what = [&](const char* field) {
      return fmt::format("field '{}' from '{}' (window {})", field, name, solid_window);
    };
    state.positions = exchange::unpack(
        participant_.receive(name, exchange::kPositions, solid_window), what(exchange::kPositions));
    const std::size_t count = state.positions.size();
    state.velocities =
        exchange::unpack(participant_.receive(name, exchange::kVelocities, solid_window), count,
                         what(exchange::kVelocities));
    state.drag = exchange::unpack(participant_.receive(name, exchange::kDrag, solid_window), count,
                                  what(exchange::kDrag));
    states.push_back(std::move(state));
  }
  return states;
}

void FlowLink::publish_samples(const std::string& solid,
                               std::span<const Eigen::Vector3d> ambient_velocity,
                               std::span<const double> water_fraction) {
  participant_.publish(exchange::ambient_velocity_field(solid), exchange::pack(ambient_velocity));
  participant_.publish(exchange::water_fraction_field(solid),
                       std::vector<double>(water_fraction.begin(), water_fraction.end()));
}

}  // namespace cosim::coupler
