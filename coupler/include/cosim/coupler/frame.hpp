// The one world frame of a coupled run (docs/architecture.md) and how a participant's own
// coordinates map onto it. Positions, velocities and forces cross the coupler only in the world
// frame; a 2D solver computes in the x-z plane of the world, which its library stores as its
// first two coordinates (a, b) = (x, z), and stands for a slice `span` metres wide along y.
#pragma once

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

namespace cosim::scenario {
struct WorldSettings;
}

namespace cosim::coupler {

// Name of the frame convention every participant of this build works in.
inline constexpr const char* kWorldFrame = "right-handed; x along the flow, y across, z up";

// What a participant declares at the handshake.
struct FrameDeclaration {
  std::string frame = kWorldFrame;
  int dimension = 3;
  double span = 0.0;  // [m] width along y a 2D participant stands for (0 for 3D)
  Eigen::Vector3d gravity = Eigen::Vector3d(0.0, 0.0, -9.81);  // [m/s^2], world frame
  // Whether its reports carry a stable dt that may shorten an adaptive window. The coupler sizes
  // window k + 1 as soon as every participant that does has finished window k, and grants it
  // ahead of the others. A declaration without the field (an older build) counts as limiting.
  bool limits_window = false;

  std::string to_json() const;
  // `who` names the sender in the error message of a malformed declaration.
  static FrameDeclaration from_json(const std::string& text, const std::string& who);
};

// Checks every participant's declaration against the scene's world and against each other.
// Returns an empty string when they agree, else a message naming the participants that differ.
std::string check_declarations(
    const std::vector<std::pair<std::string, FrameDeclaration>>& declarations,
    const scenario::WorldSettings& world);

// World <-> a participant's own coordinates. 3D: the identity. 2D: world (x, y, z) is solver
// (x, z, 0); a world force [N] is a solver force per span width [N/m] (its y part has no place in
// the plane and is reported by the caller, not applied).
class SolverFrame {
 public:
  SolverFrame() = default;
  SolverFrame(int dimension, double span);

  int dimension() const { return dimension_; }
  double span() const { return span_; }
  Eigen::Vector3d to_solver(const Eigen::Vector3d& world) const;
  Eigen::Vector3d to_world(const Eigen::Vector3d& solver) const;
  Eigen::Vector3d force_to_solver(const Eigen::Vector3d& world_force) const;
  Eigen::Vector3d force_to_world(const Eigen::Vector3d& solver_force) const;
  // The part of a world vector the solver cannot represent (2D: the y component).
  Eigen::Vector3d out_of_plane(const Eigen::Vector3d& world) const;

 private:
  int dimension_ = 3;
  double span_ = 1.0;
};

}  // namespace cosim::coupler
