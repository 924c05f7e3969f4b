// Resolved thin solids in the 2D fluid (FluidSystem::set_moving_walls, plate_pressure_loads): a
// line of wall particles moving with a plate of no thickness, thin partitions along it so that
// the water on its two sides meets only through the plate, and the pressure load of each node.
//
// The load is the pressure difference across the plate integrated over each node's share of its
// length: f_k = (p_-(k) - p_+(k)) l_k n_k per unit span [N/m], n_k the unit normal of the plate
// at node k, p_+ and p_- the mean pressure of the fluid particles within the radius on each side,
// each carried hydrostatically to the node's height.
// (The wall particles' own pressure, one value shared by both sides, cannot give it: with the
// minimum gradient form the high-pressure side's terms p_w - p^_i vanish and the plate would be
// pushed into the high pressure.) The pressure follows the plate's motion through the pressure
// equation, so the load carries the water's inertia (added mass) and the pressure drag of a
// resolved interface (MPS-FEM: Hwang et al. 2014, J. Fluids Struct.; the partitioned plate of
// Causin, Gerbeau & Nobile 2005, CMAME 194).
#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

#include "cosim/fluid_mps/fluid_system.hpp"

namespace cosim::mps {

void FluidSystem::set_moving_walls(std::vector<int> particles,
                                   std::vector<PartitionSegment> segments) {
  for (const int i : particles) {
    if (i < 0 || i >= particle_count() || kinds_[i] != ParticleKind::wall) {
      throw std::invalid_argument("set_moving_walls: particle " + std::to_string(i) +
                                  " is not a wall particle");
    }
  }
  if (!scene_partitions_kept_) {
    scene_partitions_ = parameters_.partitions;
    scene_partitions_kept_ = true;
  }
  parameters_.partitions = scene_partitions_;
  parameters_.partitions.insert(parameters_.partitions.end(), segments.begin(), segments.end());
  neighbours_valid_ = false;  // pairs across the new partitions are cut at the next search
}

std::vector<Eigen::Vector3d> plate_pressure_loads(const FluidSystem& system,
                                                  const std::vector<Eigen::Vector3d>& nodes,
                                                  double radius) {
  if (!(radius > 0.0)) throw std::invalid_argument("plate_pressure_loads: radius must be positive");
  const std::size_t count = nodes.size();
  std::vector<Eigen::Vector3d> loads(count, Eigen::Vector3d::Zero());
  if (count < 2) return loads;
  const auto& x = system.positions();
  const auto& p = system.pressures();
  const auto& periodic = system.parameters().periodic;
  const Eigen::Vector3d& gravity = system.parameters().gravity;
  const double rho = system.parameters().density;
  const auto near = system.fluid_particles_near(nodes, radius);
  for (std::size_t k = 0; k < count; ++k) {
    // Tangent over the neighbouring nodes (one-sided at the ends), normal in the plane.
    const Eigen::Vector3d& before = nodes[k == 0 ? 0 : k - 1];
    const Eigen::Vector3d& after = nodes[k + 1 == count ? k : k + 1];
    const Eigen::Vector3d chord = after - before;
    if (!(chord.norm() > 0.0)) continue;
    const Eigen::Vector3d normal = Eigen::Vector3d(-chord.y(), chord.x(), 0.0).normalized();
    double share = 0.0;  // half of each adjacent link
    if (k > 0) share += 0.5 * (nodes[k] - nodes[k - 1]).norm();
    if (k + 1 < count) share += 0.5 * (nodes[k + 1] - nodes[k]).norm();
    double sum[2] = {0.0, 0.0};
    int found[2] = {0, 0};
    for (const int i : near[k]) {
      const Eigen::Vector3d offset = periodic.wrap(x[i] - nodes[k]);
      const double side = offset.dot(normal);
      if (side == 0.0) continue;
      const int s = side > 0.0 ? 0 : 1;
      // The particle's pressure carried hydrostatically to the node: else the two sides'
      // particles, a layer l0 thick each, would give a plate without volume the buoyancy of a
      // slab 2 radius thick.
      sum[s] += carried_hydrostatically(p[i], -offset, rho, gravity);
      ++found[s];
    }
    const double plus = found[0] > 0 ? sum[0] / found[0] : 0.0;  // no water: p = 0
    const double minus = found[1] > 0 ? sum[1] / found[1] : 0.0;
    loads[k] = (minus - plus) * share * normal;
  }
  return loads;
}

namespace {

double distance_to_polyline(const Eigen::Vector3d& x, const std::vector<Eigen::Vector3d>& points) {
  double nearest = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < points.size(); ++k) {
    const Eigen::Vector3d& a = points[k];
    const Eigen::Vector3d ab = (k + 1 < points.size() ? points[k + 1] : a) - a;
    const double length2 = ab.squaredNorm();
    const double t = length2 > 0.0 ? std::clamp((x - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
    nearest = std::min(nearest, (x - (a + t * ab)).norm());
  }
  return nearest;
}

}  // namespace

AppendedWall append_wall_particles(MpsState& state, const std::vector<Eigen::Vector3d>& positions,
                                   double clearance) {
  AppendedWall wall;
  state.pressure_setup = PressureSetupState{};  // its keys are the particles before the edit
  for (std::size_t i = 0; i < state.positions.size(); ++i) {
    if (state.kinds[i] == ParticleKind::fluid &&
        distance_to_polyline(state.positions[i], positions) < clearance) {
      state.kinds[i] = ParticleKind::inactive;
      state.velocities[i].setZero();
      ++wall.cleared;
    }
  }
  for (const auto& x : positions) {
    wall.particles.push_back(static_cast<int>(state.positions.size()));
    state.positions.push_back(x);
    state.velocities.push_back(Eigen::Vector3d::Zero());
    state.pressures.push_back(0.0);
    state.kinds.push_back(ParticleKind::wall);
  }
  return wall;
}

}  // namespace cosim::mps
