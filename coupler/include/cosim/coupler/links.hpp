// The two sides of the flow/solid exchange described in exchange.hpp, on top of the
// participant API: a solid publishes its state and gets the ambient flow over its window; the
// flow gets every solid's state and answers with samples. Process mains use these, so all
// solvers and stand-ins follow the same rules.
#pragma once

#include <Eigen/Core>
#include <map>
#include <span>
#include <string>
#include <tuple>
#include <vector>

#include "cosim/checkpoint/archive.hpp"
#include "cosim/coupler/exchange.hpp"
#include "cosim/coupler/frame.hpp"
#include "cosim/coupler/participant.hpp"
#include "cosim/scenario/scene.hpp"

namespace cosim::coupler {

struct AmbientFlow {
  std::vector<Eigen::Vector3d> velocity;
  std::vector<double> water_fraction;  // 1 submerged, 0 dry
  // World z of the free surface above each point; -inf: no water above; NaN: the flow does not
  // know (use water_fraction).
  std::vector<double> surface_elevation;
  // coupling.resolved_plants: the flow's pressure force on each node over the window, world [N]
  // (empty otherwise).
  std::vector<Eigen::Vector3d> fluid_load;
};

class SolidLink {
 public:
  SolidLink(Participant& participant, const scenario::Scene& scene, std::size_t point_count);

  // `volumes` [m^3]: the water each point displaces; sent when given (exchange::displaces_water
  // says which solids must).
  void publish_state(std::span<const Eigen::Vector3d> positions,
                     std::span<const Eigen::Vector3d> velocities,
                     std::span<const Eigen::Vector3d> drag, std::span<const double> volumes = {});
  // The same at the end of a window of length `dt` that started at `start` (the positions the
  // solid had then). Under an implicit scheme a solid the flow resolves hands it its window-mean
  // velocity instead of `velocities` (exchange::resolved_velocity).
  void publish_window_state(std::span<const Eigen::Vector3d> start, double dt,
                            std::span<const Eigen::Vector3d> positions,
                            std::span<const Eigen::Vector3d> velocities,
                            std::span<const Eigen::Vector3d> drag,
                            std::span<const double> volumes = {});
  // The flow at the start and the end of `window` (index >= 1). Without a flow provider in the
  // scene: still and dry.
  std::pair<AmbientFlow, AmbientFlow> ambient(const Window& window);

 private:
  // `sender`'s samples of (flow_window, iteration): the flow's, or the coupler's relaxed ones.
  AmbientFlow receive(const std::string& sender, int64_t flow_window, int32_t iteration = 0);

  Participant& participant_;
  std::string flow_name_;  // empty: no flow provider
  bool serial_ = true;
  bool implicit_ = false;
  bool resolved_ = false;  // exchange::resolved_by_flow: the flow sends a fluid load
  std::size_t point_count_;
  std::map<std::tuple<std::string, int64_t, int32_t>, AmbientFlow> cache_;
};

// One solid as the flow sees it in a window, in the flow's own coordinates (SolverFrame): where
// its points are, how they move, and the force the flow must apply at each of them throughout
// the window [N; N per metre of span in 2D].
struct SolidForcing {
  std::string name;
  std::vector<Eigen::Vector3d> positions;
  std::vector<Eigen::Vector3d> velocities;
  std::vector<Eigen::Vector3d> reaction;
  // The water each point displaces, in the flow's measure: m^3 in 3D, m^2 per span width in 2D
  // (as forces are per span). A flow that leaves this volume to the solids takes no buoyancy
  // reaction either: its own pressure then carries the solids' weight (locally averaged
  // equations; the solids' buoyancy is the -V grad p of that pressure).
  std::vector<double> volumes;
  // coupling.resolved_plants, for a solid the flow resolves (FlowLink::resolves; empty
  // otherwise): each point's path through the window (exchange::resolved_path), in the flow's
  // coordinates.
  std::vector<Eigen::Vector3d> path_start;
  std::vector<Eigen::Vector3d> path_velocity;
};

// The flow's side of the exchange. It holds the exchange rules, so every flow provider follows
// them alike:
// - reaction sign: the flow takes minus the drag each solid reports;
// - one-window lag: in window k it takes the drag of the solids' window k-1, rescaled by
//   dt_{k-1} / dt_k so that the impulse it receives equals the one the solids took;
// - frame: world positions, velocities and forces to the flow's own coordinates (2D: the x-z
//   plane, forces per metre of span), samples back to the world;
// - booking: the world impulse handed to the flow, and the out-of-plane part a 2D flow cannot
//   take.
class FlowLink {
 public:
  FlowLink(Participant& participant, const scenario::Scene& scene, SolverFrame frame = {});

  // with_volumes: also the water the solids displace (SolidForcing::volumes; zeros for solids
  // that displace none).
  std::vector<SolidForcing> receive_solids(const Window& window, bool with_volumes = false);
  // Samples at the solid's points, in the flow's coordinates. surface_elevation: the vertical
  // coordinate of the free surface above each point (empty: unknown).
  void publish_samples(const std::string& solid, std::span<const Eigen::Vector3d> ambient_velocity,
                       std::span<const double> water_fraction,
                       std::span<const double> surface_elevation = {});
  // coupling.resolved_plants: the flow resolves this solid (wall particles at its points).
  bool resolves(const std::string& solid) const {
    return exchange::resolved_by_flow(resolved_plants_, solid);
  }
  // The force the flow's pressure exerted on each of the solid's points over the window, in the
  // flow's coordinates [N; N per metre of span in 2D]; sent as the solid's fluid load in the world
  // [N] (a 2D flow's wall spans the slice: the force per span times the span).
  void publish_fluid_load(const std::string& solid, std::span<const Eigen::Vector3d> load);

  // World impulse [N s] of every reaction handed to the flow so far, in its plane (the flow
  // applies it over each window: reaction * dt summed), and the part a 2D flow has no place for
  // (along y). Their sum is minus the solids' drag impulse (one window later).
  const Eigen::Vector3d& booked_impulse() const { return booked_impulse_; }
  const Eigen::Vector3d& out_of_plane_impulse() const { return out_of_plane_impulse_; }
  const SolverFrame& frame() const { return frame_; }

  // The link's running state (last window length, booked impulses) for checkpoints.
  void save_checkpoint(checkpoint::Writer& out) const;
  void load_checkpoint(const checkpoint::Reader& in);

 private:
  Participant& participant_;
  std::vector<std::string> solids_;
  SolverFrame frame_;
  bool implicit_ = false;
  bool resolved_plants_ = false;
  double previous_dt_ = 0.0;  // window 1 takes the solids' window-0 drag, which is zero
  Eigen::Vector3d booked_impulse_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d out_of_plane_impulse_ = Eigen::Vector3d::Zero();
};

}  // namespace cosim::coupler
