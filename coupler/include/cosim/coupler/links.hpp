// The two sides of the flow/solid exchange described in exchange.hpp, on top of the
// participant API: a solid publishes its state and gets the ambient flow over its window; the
// flow gets every solid's state and answers with samples. Process mains use these, so all
// solvers and stand-ins follow the same rules.
#pragma once

#include <Eigen/Core>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "cosim/coupler/exchange.hpp"
#include "cosim/coupler/participant.hpp"
#include "cosim/scenario/scene.hpp"

namespace cosim::coupler {

struct AmbientFlow {
  std::vector<Eigen::Vector3d> velocity;
  std::vector<double> water_fraction;  // 1 submerged, 0 dry
};

class SolidLink {
 public:
  SolidLink(Participant& participant, const scenario::Scene& scene, std::size_t point_count);

  void publish_state(std::span<const Eigen::Vector3d> positions,
                     std::span<const Eigen::Vector3d> velocities,
                     std::span<const Eigen::Vector3d> drag);
  // The flow at the start and the end of `window` (index >= 1). Without a flow provider in the
  // scene: still and dry.
  std::pair<AmbientFlow, AmbientFlow> ambient(const Window& window);

 private:
  AmbientFlow receive(int64_t flow_window);

  Participant& participant_;
  std::string flow_name_;  // empty: no flow provider
  bool serial_ = true;
  std::size_t point_count_;
  std::map<int64_t, AmbientFlow> cache_;
};

struct SolidState {
  std::string name;
  std::vector<Eigen::Vector3d> positions;
  std::vector<Eigen::Vector3d> velocities;
  std::vector<Eigen::Vector3d> drag;
};

class FlowLink {
 public:
  FlowLink(Participant& participant, const scenario::Scene& scene);

  // Every solid's state as the flow uses it in `window` (exchange::solid_window_for_flow).
  std::vector<SolidState> receive_solids(const Window& window);
  void publish_samples(const std::string& solid, std::span<const Eigen::Vector3d> ambient_velocity,
                       std::span<const double> water_fraction);

 private:
  Participant& participant_;
  std::vector<std::string> solids_;
};

}  // namespace cosim::coupler
