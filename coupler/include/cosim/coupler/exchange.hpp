// The data a flow provider and its solids exchange, and which window each side reads. Both
// sides use these names and rules, so a scene's scheme is decided in one place.
//
// Every window k (0 = initial state, dt = 0):
//   solid S publishes  "positions", "velocities" (3 per node or element) and "drag" (the mean
//                      force the fluid exerted on each node over the window; the flow takes
//                      minus it), all of window k;
//   the flow publishes "ambient_velocity@S" (3 per node), "water_fraction@S" (1 per node) and
//                      "surface_elevation@S" (world z of the free surface above each node; NaN
//                      when the flow does not know, -inf when there is no water above)
//                      at the end of window k, sampled where S's nodes were at the end of the
//                      window it read.
// The flow in window k reads the solids' window k-1 (window 0: window 0). A solid in window k
// reads the flow's windows k-1 (begin) and k (end) in the serial-explicit scheme, and window
// k-1 for both in the parallel-explicit scheme, so flow and solids compute at the same time.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace cosim::coupler::exchange {

inline constexpr const char* kPositions = "positions";
inline constexpr const char* kVelocities = "velocities";
inline constexpr const char* kDrag = "drag";
// Volume [m^3] of water each solid point displaces. Sent by the solids that displace water:
// debris; plants are thin stems whose volume the flows leave out.
inline constexpr const char* kVolumes = "volumes";
inline bool displaces_water(const std::string& solid) {
  return solid == "debris_dem";
}

inline std::string ambient_velocity_field(const std::string& solid) {
  return "ambient_velocity@" + solid;
}
inline std::string water_fraction_field(const std::string& solid) {
  return "water_fraction@" + solid;
}
inline std::string surface_field(const std::string& solid) {
  return "surface_elevation@" + solid;
}

// coupling.resolved_plants (scenario::InterfaceSettings): the flow also publishes
// "fluid_load@S" (3 per node, world [N]): the mean force its pressure exerted over the window on
// the wall particles that stand for S's nodes. The solid takes it as its fluid load and reports
// no drag (the flow already felt the solid through those particles: no reaction to apply).
inline std::string fluid_load_field(const std::string& solid) {
  return "fluid_load@" + solid;
}
inline bool resolved_by_flow(bool resolved_plants, const std::string& solid) {
  return resolved_plants && solid == "vegetation_beam";
}

// The path a flow moves a solid it resolves along (its wall particles) through window k, from
// `start` with a constant `velocity`. Explicit schemes, and the first iteration of an implicit
// window, know only the window-start state (x_{k-1}, v_{k-1}): the wall moves on with it. Later
// implicit iterations know the iterate's window-end positions x_k as well: the wall then goes
// from the accepted window-start positions to them, velocity (x_k - x_{k-1}) / dt, so that the
// fluid and the solid agree on where the solid is at both ends of a converged window (placed at
// x_k and moved on with v_k, the wall would run a whole window ahead of the solid).
struct ResolvedPath {
  Eigen::Vector3d start;
  Eigen::Vector3d velocity;
};
inline ResolvedPath resolved_path(const Eigen::Vector3d& start_position,
                                  const Eigen::Vector3d& start_velocity,
                                  const Eigen::Vector3d* end_position, double dt) {
  if (end_position == nullptr || !(dt > 0.0)) return {start_position, start_velocity};
  return {start_position, (*end_position - start_position) / dt};
}

// The velocity a solid the flow resolves hands the flow at the end of an implicit window: the
// mean over the window, (x_k - x_{k-1}) / dt, not the point's velocity at that instant. The
// first iteration of the next window extrapolates the wall with it, which is the linear
// extrapolation of the converged positions preCICE starts a window from; the instant's velocity
// also carries vibrations far faster than the fluid's step (a light blade flapping on the bed,
// 2 ms windows: nodes at 0.4-2.3 m/s at a window's end while they moved 0.005 m/s on average),
// and extrapolated it swept the wall millimetres into the water. Explicit schemes keep the
// instant's velocity: their wall never meets the solid again within the window, and the Taylor
// step x + v dt ends closer to it (light_blade_bed at 0.5 ms windows: at most 1.49 mm off,
// against 3.49 mm with the mean).
inline Eigen::Vector3d resolved_velocity(const Eigen::Vector3d& start_position,
                                         const Eigen::Vector3d& end_position,
                                         const Eigen::Vector3d& end_velocity, double dt) {
  if (!(dt > 0.0)) return end_velocity;
  return (end_position - start_position) / dt;
}

// Window of the solids' data the flow uses in window `flow_window`.
inline int64_t solid_window_for_flow(int64_t flow_window) {
  return std::max<int64_t>(flow_window - 1, 0);
}

struct FlowWindows {
  int64_t begin = 0;  // ambient at the start of the window
  int64_t end = 0;    // ambient at the end of the window
};
// Windows of flow data a solid uses in window `solid_window` (>= 1).
inline FlowWindows flow_windows_for_solid(int64_t solid_window, bool serial_scheme) {
  const int64_t previous = std::max<int64_t>(solid_window - 1, 0);
  return serial_scheme ? FlowWindows{previous, solid_window} : FlowWindows{previous, previous};
}

// Implicit schemes (serial-implicit, parallel-implicit) iterate window k: iteration i >= 1 runs
// again from the state at the window start. Iteration 0 reads what the explicit scheme reads
// (window k-1 taken at the iteration the coupler accepted for it), so with one iteration per
// window an implicit scheme gives the explicit one's results (except for a solid the flow
// resolves, whose velocity is then its window mean: resolved_velocity). In iteration i >= 1 the
// flow reads the coupler's fields of (k, i), "positions@S", "velocities@S", "drag@S" (and
// "volumes@S"): the solids' window k, the fields the flow reads relaxed by the coupler's
// accelerator (a resolved solid's positions only; its velocities and drag as it answered), its
// drag acting over window k itself (no lag, no rescaling). A solid reads the flow's
// (k-1, accepted) at the window start and, at the end, the flow's (k, i) in the serial scheme, or
// in the parallel one the coupler's (k, i) samples (the flow's window k, relaxed; iteration 0:
// the window start held constant).
inline constexpr const char* kCoupler = "coupler";
inline std::string solid_field_for_flow(const std::string& field, const std::string& solid) {
  return field + "@" + solid;
}

inline std::vector<double> pack(std::span<const Eigen::Vector3d> vectors) {
  std::vector<double> values;
  values.reserve(vectors.size() * 3);
  for (const auto& vector : vectors)
    values.insert(values.end(), {vector.x(), vector.y(), vector.z()});
  return values;
}

// `what` names the field and sender for the error message.
inline std::vector<Eigen::Vector3d> unpack(std::span<const double> values, std::size_t expected,
                                           const std::string& what) {
  if (values.size() != expected * 3) {
    throw std::runtime_error(what + ": expected " + std::to_string(expected * 3) +
                             " values (3 per point), got " + std::to_string(values.size()));
  }
  std::vector<Eigen::Vector3d> vectors(expected);
  for (std::size_t i = 0; i < expected; ++i) {
    vectors[i] = Eigen::Vector3d(values[3 * i], values[3 * i + 1], values[3 * i + 2]);
  }
  return vectors;
}

inline std::vector<Eigen::Vector3d> unpack(std::span<const double> values,
                                           const std::string& what) {
  if (values.size() % 3 != 0) {
    throw std::runtime_error(what + ": " + std::to_string(values.size()) +
                             " values is not a whole number of 3-vectors");
  }
  return unpack(values, values.size() / 3, what);
}

}  // namespace cosim::coupler::exchange
