// Semi-implicit MPS fluid (Koshizuka-Oka; seed 000 section 2(1), seed 001 section 2).
#pragma once

#include <Eigen/Core>
#include <optional>
#include <utility>
#include <vector>

#include "cosim/fluid_mps/hydrostatic_background.hpp"
#include "cosim/fluid_mps/kernels.hpp"
#include "cosim/fluid_mps/neighbour_grid.hpp"
#include "cosim/fluid_mps/parameters.hpp"
#include "cosim/fluid_mps/pressure_solver.hpp"
#include "cosim/fluid_mps/spatial_order.hpp"
#include "cosim/fluid_mps/stage_seconds.hpp"

namespace cosim::mps {

struct StepReport {
  double dt = 0.0;
  StageSeconds stage_seconds;
  int pcg_iterations = 0;
  double pcg_residual = 0.0;
  bool pcg_converged = true;  // false: max iterations hit; the step still completes
  double max_speed = 0.0;     // fluid particles, end of step
  int surface_particles = 0;  // fluid and wall particles with the Dirichlet p = 0 condition
  int collisions = 0;         // fluid-particle contacts corrected (a fluid-fluid pair counts twice)
  int pressure_unknowns = 0;
  // Neighbour searches in this step: the pair list (with a skin of kSkinOverL0 l0) is kept while
  // no particle has moved half the skin since it was built, so 0 or 1, rarely 2.
  int neighbour_searches = 0;
  // Viscous force of the wall and dummy particles on the fluid (Laplacian model, explicit part at
  // r^n) [N in 3D, N/m in 2D]: the bed shear of a channel.
  Eigen::Vector3d wall_viscous_force = Eigen::Vector3d::Zero();
  // Momentum the fluid received in this step from the collision model and from the pressure
  // gradient [N s, N s/m in 2D], and the parts of those that came from wall particles. The
  // fluid-fluid parts of the pressure gradient do not cancel exactly (the p_j - p_min form is not
  // antisymmetric): pressure_impulse - wall_pressure_impulse is that non-conservation.
  Eigen::Vector3d collision_impulse = Eigen::Vector3d::Zero();
  Eigen::Vector3d wall_collision_impulse = Eigen::Vector3d::Zero();
  Eigen::Vector3d pressure_impulse = Eigen::Vector3d::Zero();
  Eigen::Vector3d wall_pressure_impulse = Eigen::Vector3d::Zero();
  // Momentum the fluid received in this step from the point forces (set_point_forces).
  Eigen::Vector3d external_impulse = Eigen::Vector3d::Zero();
  // Gravity and the periodic driving body force on the fluid particles in this step. With the
  // wall viscous force, collision, pressure and external impulses it is everything that changes
  // the fluid's momentum (fluid-fluid viscosity and collisions cancel in pairs): the budget of a
  // closed domain closes to round-off.
  Eigen::Vector3d body_impulse = Eigen::Vector3d::Zero();
  // Momentum the shifted particles took with shifted_velocity: taylor (zero with kept): no force
  // gave it, so it is booked apart for the budget to close.
  Eigen::Vector3d shifting_impulse = Eigen::Vector3d::Zero();
};

// Result of apply_point_forces: forces of points with no fluid inside the radius are dropped.
struct ForceDelivery {
  int undelivered_points = 0;
  Eigen::Vector3d undelivered_force = Eigen::Vector3d::Zero();
};

// Snapshot for restart (see restart.hpp for the binary file).
struct MpsState {
  std::vector<Eigen::Vector3d> positions;
  std::vector<Eigen::Vector3d> velocities;
  std::vector<double> pressures;
  std::vector<ParticleKind> kinds;
  double time = 0.0;
  long step = 0;
  // The pressure solver's set-up in reuse (by particle id): restored with the particles, it
  // lets a restarted run continue with the same bits. Empty (kept false): a fresh set-up.
  PressureSetupState pressure_setup;
};

class FluidSystem {
 public:
  // Skin of the pair list [l0]: pairs are searched within the largest radius + skin.
  static constexpr double kSkinOverL0 = 0.5;

  FluidSystem(MpsParameters parameters, ParticleSet particles);
  // Restart: the state of save_state(); continuing gives the same bits as a straight run.
  FluidSystem(MpsParameters parameters, const MpsState& state);

  int particle_count() const { return static_cast<int>(positions_.size()); }
  const std::vector<Eigen::Vector3d>& positions() const { return positions_; }
  const std::vector<Eigen::Vector3d>& velocities() const { return velocities_; }
  const std::vector<double>& pressures() const { return pressures_; }
  const std::vector<ParticleKind>& kinds() const { return kinds_; }
  // Number densities at the temporary positions r* of the last step (initial positions before);
  // NaN for dummy particles, whose own density no stage uses and which is not computed.
  const std::vector<double>& number_densities() const { return number_densities_; }
  const MpsParameters& parameters() const { return parameters_; }
  double time() const { return time_; }
  long step_count() const { return step_; }
  double particle_mass() const { return particle_mass_; }
  double n0_density() const { return density_sums_.n0; }
  double n0_gradient() const { return gradient_sums_.n0; }
  double n0_laplacian() const { return laplacian_sums_.n0; }
  double lambda_laplacian() const;  // [m^2]

  // dt = min(courant l0 / u_max, diffusion_number l0^2 / nu, max_dt).
  double stable_dt() const;

  // One semi-implicit step: explicit viscosity + gravity + external forces, collision model,
  // pressure Poisson equation with free-surface Dirichlet condition, pressure correction.
  // Throws StabilityError on NaN, escaped particle or runaway speed.
  StepReport step(double dt);
  // The pressure equation of the last step, rows in the internal particle order (for checks:
  // its CG products read the upper triangle only with MpsParameters::pressure_product).
  const SparseRows& pressure_matrix() const { return matrix_; }

  // Ensemble average of fluid particle velocities within `radius` of each point (seed 000: the
  // surrounding velocity of a plant particle, r_ev = 2 d_veg). water_fraction: fluid particles
  // within radius / particles of a full lattice within radius, clipped to [0, 1]. Points with no
  // fluid get zero velocity and fraction 0. This, fluid_particles_near and set_point_forces share
  // a kept grid: call them from one thread at a time.
  std::vector<Eigen::Vector3d> sample_velocity(const std::vector<Eigen::Vector3d>& points,
                                               double radius,
                                               std::vector<double>* water_fraction = nullptr) const;
  // Indices of the fluid particles within `radius` of each point (periodic distances), in
  // increasing order: the particles sample_velocity averages.
  std::vector<std::vector<int>> fluid_particles_near(const std::vector<Eigen::Vector3d>& points,
                                                     double radius) const;

  // Free-surface height above each point: the vertical coordinate (y in 2D, z in 3D) of the
  // highest fluid particle of each column l0 wide, averaged over the wet columns within a
  // horizontal distance `radius` of the point, plus l0 / 2 (the particle's own extent). -inf
  // where no fluid lies within reach. A solid computes its submerged volume from it.
  void sample_surface(const std::vector<Eigen::Vector3d>& points, double radius,
                      std::vector<double>& surface) const;

  // Forces [N in 3D, N/m in 2D] that replace the previous ones and act in every step until they
  // are set again (a coupling window split into several fluid steps takes them in each), each
  // shared equally by the fluid particles within `radius` at the time of the call (the adjoint
  // of sample_velocity), so the momentum given per step is exactly sum(force) * dt
  // (StepReport::external_impulse). Forces of points with no fluid nearby are reported, not
  // applied. Empty vectors clear the forces.
  ForceDelivery set_point_forces(const std::vector<Eigen::Vector3d>& points,
                                 const std::vector<Eigen::Vector3d>& forces, double radius);
  // Several sets of point forces at once (one per solid), replacing the previous ones.
  ForceDelivery set_point_forces(
      const std::vector<std::pair<std::vector<Eigen::Vector3d>, std::vector<Eigen::Vector3d>>>&
          point_forces,
      double radius);

  // Volumes the solids occupy in the fluid [m^3 in 3D, m^2 per span in 2D] at points, kept until
  // set again (empty: none). The fluid then leaves them to the solids, as in the locally
  // averaged equations of unresolved CFD-DEM (Anderson & Jackson 1967; for MPS, Sakai et al.,
  // Chem. Eng. J. 200-202 (2012) 663-672): each volume is spread over `radius` with a normalised
  // kernel into a solid fraction phi_i at the fluid particles, whose incompressible number
  // density becomes (1 - phi_i) n0. Solids moving through the water thus displace it (a level
  // that rises, waves radiated by a heaving body, a return flow around sinking ones). Throws if
  // the radius is not positive or a volume is negative.
  void set_solid_volumes(std::vector<Eigen::Vector3d> points, std::vector<double> volumes,
                         double radius);
  // phi_i of the last step (0 for every particle without solid volumes; all sizes n).
  const std::vector<double>& solid_fractions() const { return solid_fraction_; }
  // Largest phi before the cap kMaximumSolidFraction, over the last step.
  double largest_solid_fraction() const { return largest_solid_fraction_; }
  static constexpr double kMaximumSolidFraction = 0.7;

  // Sum of m u over fluid particles [kg m/s in 3D, kg m/s per m in 2D].
  Eigen::Vector3d total_fluid_momentum() const;

  MpsState save_state() const;

  // Open boundaries (boundaries.hpp) change particles between steps: kind, position and velocity
  // of particle i (pressure reset to 0). Arrays keep their size; inactive particles are pooled.
  void set_particle(int i, ParticleKind kind, const Eigen::Vector3d& position,
                    const Eigen::Vector3d& velocity);
  // Velocity of a wall or dummy particle (a moving wall), kept until changed.
  void set_velocity(int i, const Eigen::Vector3d& velocity);

  // A resolved thin solid (moving_walls.cpp): wall particles (kind wall, placed with
  // set_particle) that stand for a plate of no thickness in a 2D flow, and the thin partitions
  // along it (keep_walls: fluid-fluid pairs across the plate are cut, its particles seen from both
  // sides). Replaces the previous set; the scene's own partitions stay. Throws unless they are
  // wall particles.
  void set_moving_walls(std::vector<int> particles, std::vector<PartitionSegment> segments);

 private:
  struct StepConstants;  // radii, lattice constants and factors of one step (fluid_step.cpp)

  void initialise();
  void check_stability(long step) const;
  std::optional<StabilityError> instability(long step, int i) const;
  double max_fluid_speed() const;  // [m/s], over the fluid particles
  // Stages of step(), in order (fluid_step.cpp).
  void predict(const StepConstants& c, StepReport& report);
  void collide(const StepConstants& c, StepReport& report);
  void measure_density(const StepConstants& c, StepReport& report);
  void measure_background();
  void assemble_pressure_equation(const StepConstants& c);
  struct AssemblyBuffer;
  void assemble_laplacian_rows(double radius, double diagonal_shift, SparseRows& matrix,
                               std::vector<AssemblyBuffer>& buffers);
  void solve_pressure(StepReport& report);
  // Radius of the Laplacian the multigrid hierarchy is built from [m].
  double hierarchy_radius() const;
  void correct_with_pressure_gradient(const StepConstants& c, StepReport& report);
  void finish_step(const StepConstants& c, StepReport& report);
  // Makes the pair list valid at `x` (internal order): searched again if a particle has moved
  // half the skin since the last search or the particle kinds changed. With `reorder` (only at
  // the start of a step, before any stage has written its arrays) a new search also puts the
  // particles in cell order and gathers the state again in that order (fluid_pairs.cpp).
  void update_neighbours(const std::vector<Eigen::Vector3d>& x, StepReport& report,
                         bool reorder = false);
  // near_: the pairs of the list closer than `cutoff` at `x`, with their distances, each
  // particle's in [near_.offset[i], near_end_[i]); pairs cut by a thin partition at `x` get an
  // infinite distance.
  void find_near_pairs(const std::vector<Eigen::Vector3d>& x, double cutoff);
  // Row i of find_near_pairs (r^2 <= cutoff2); with `tail` the rest of the row is filled with
  // the particle itself at infinity, so that the partition mask can walk whole rows.
  void find_near_row(int i, const std::vector<Eigen::Vector3d>& x, double cutoff2, bool tail);
  // The same row written to index[0 ..) and distance[0 ..) (room for the list's whole row);
  // returns how many pairs it holds.
  std::int64_t find_row(int i, const std::vector<Eigen::Vector3d>& x, double cutoff2, int* index,
                        double* distance) const;
  // (1 + 1e-12) cutoff^2: pairs are dropped on r^2 with a margin well above rounding; the stages
  // compare the distance itself with their radii.
  static double near_cutoff2(double cutoff) { return cutoff * cutoff * (1.0 + 1e-12); }
  // Where the stages see inactive particle i: far outside any domain (1e9 m, beyond the
  // periodic axis too) and 1 km from any other, so that every pair a stale pair list still
  // holds with it is out of reach. Then a particle leaving the flow (set_particle) needs no new
  // neighbour search: it drops out of every stage's pairs at once, and a particle entering it
  // has moved from there by far more than the skin, which triggers the search.
  static Eigen::Vector3d parked_position(int i) {
    const double far = 1e9 + 1e3 * static_cast<double>(i);
    return Eigen::Vector3d(far, far, far);
  }
  // The public arrays (particle order) into the internal ones (order_), and back. Inactive
  // particles enter the internal positions at parked_position(i), not at their own.
  void gather_state();
  void scatter_state();
  // phi_ (internal order) at r* from update_solid_fractions.
  void update_phi();
  // phi_i at `x` from the solid volumes (solid_volume.cpp); zeros without them.
  void update_solid_fractions(const std::vector<Eigen::Vector3d>& x);

  MpsParameters parameters_;
  std::vector<Eigen::Vector3d> positions_;
  std::vector<Eigen::Vector3d> velocities_;
  std::vector<double> pressures_;
  std::vector<ParticleKind> kinds_;
  std::vector<double> number_densities_;
  std::vector<Eigen::Vector3d> external_accelerations_;
  std::vector<Eigen::Vector3d> solid_points_;
  std::vector<double> solid_volumes_, solid_fraction_;
  // set_moving_walls: the scene's own partitions the moving ones are added to.
  std::vector<PartitionSegment> scene_partitions_;
  bool scene_partitions_kept_ = false;
  double solid_radius_ = 0.0, largest_solid_fraction_ = 0.0;
  double time_ = 0.0;
  long step_ = 0;
  double particle_mass_ = 0.0;
  LatticeSums density_sums_, gradient_sums_, laplacian_sums_;
  Eigen::AlignedBox3d domain_box_;  // escape box: domain, z extent of 2D runs made non-empty

  // The stages work on particles in an internal order along the cells of the last search
  // (memory locality): order_[k] is the particle at place k, rank_[i] the place of particle i.
  // The public arrays above stay in particle order. Every sum over partners runs in particle
  // order and every reduction over particles too, so no result depends on the internal order or
  // on when it changed: a restarted run (which starts from particle order) and runs on any
  // number of threads give the same bits.
  std::vector<int> order_, rank_;
  std::vector<Eigen::Vector3d> x_, u_, acceleration_;  // r^n, u^n, point forces / m
  std::vector<double> p_, phi_, density_star_;         // p^n, solid fraction, n* (internal)
  std::vector<ParticleKind> kind_;

  // Pair list of every operator: all pairs within the largest radius plus the skin at the
  // positions of the last search, each particle's partners in ascending particle order.
  // Operators skip pairs beyond their own radius, so the sums do not depend on when the list
  // was built (a restarted run gives the same bits).
  NeighbourList neighbours_;
  NeighbourSearchWork search_work_;  // the search's buffers, kept for the next search
  NeighbourList near_;               // find_near_pairs: same offsets as neighbours_
  std::vector<std::int64_t> near_end_;
  // One per thread: a row of pairs that only its own stage reads (find_row), kept in L1.
  struct PairRow {
    std::vector<int> index;
    std::vector<double> distance;
  };
  std::vector<PairRow> pair_rows_;
  std::vector<Eigen::Vector3d> search_positions_, scratch_, unshifted_velocity_;
  std::vector<char> include_, own_row_;  // grid membership; rows searched (not dummies)
  bool neighbours_valid_ = false;
  PressureSolver pressure_solver_;
  // Work arrays of the step, kept so that a step allocates nothing once sizes have settled.
  std::vector<Eigen::Vector3d> velocity_star_, position_star_, wall_viscous_, correction_,
      wall_correction_, pressure_change_, wall_pressure_change_, untrusted_change_,
      untrusted_wall_change_, background_taylor_;
  std::vector<double> density_now_, divergence_, rhs_, solution_, pressure_, minimum_,
      full_minimum_, dynamic_pressure_;
  BackgroundField background_;
  std::vector<char> trusted_, untrusted_;  // S > 0, S < 1: where each estimate is needed
  std::vector<int> collided_, unknown_, unknown_particle_;  // unknown_particle_: along space
  SpatialOrderWork unknown_order_work_;
  std::vector<int> row_keys_;  // particle id of each pressure unknown (the aggregation's reuse)
  std::vector<std::int64_t> row_length_;
  struct alignas(64) AssemblyBuffer {  // one thread's rows of assemble_laplacian_rows
    std::vector<int> column;
    std::vector<double> value;
  };
  // One set a matrix: on one thread a buffer and its matrix trade storage at every assembly.
  std::vector<AssemblyBuffer> assembly_buffers_, hierarchy_buffers_;
  SparseRows matrix_, hierarchy_matrix_;
  LatticeSums hierarchy_sums_;

  // Coupling hooks (coupling.cpp): the cell grid of the fluid particles near the solids' points,
  // kept while no particle has moved or changed kind (state_generation_), so that the forces
  // set before a step use the grid of the samples taken after the last one. The const hooks
  // share it, so they are called from one thread at a time (as the process does).
  struct PointGrid {
    std::uint64_t generation = 0;  // state_generation_ when built; 0: none
    double radius = 0;
    Eigen::AlignedBox3d reach;  // points within it (and the radius) find all their particles
    std::vector<int> inside;    // particle index of each grid entry, increasing
    std::vector<Eigen::Vector3d> at;
    std::optional<NeighbourGrid> grid;
  };
  // The grid for `points` (radius `radius`), built again only when needed.
  const PointGrid& point_grid(const std::vector<Eigen::Vector3d>& points, double radius) const;
  mutable PointGrid point_grid_;
  std::uint64_t state_generation_ = 1;  // bumped whenever a particle moves or changes kind
};

// A particle's pressure carried hydrostatically over `to_point` (from the particle to the point
// it is read at): pressure + rho g . to_point (Adami, Hu & Adams 2012, J. Comput. Phys. 231,
// eq. (27), a wall's own acceleration left out). Probes and plate loads read the water's pressure
// at a point this way, so that where their particles sit around the point does not count.
inline double carried_hydrostatically(double pressure, const Eigen::Vector3d& to_point,
                                      double density, const Eigen::Vector3d& gravity) {
  return pressure + density * gravity.dot(to_point);
}

// Pressure load [N per m of span] on each node of a plate of no thickness along the polyline
// `nodes` (2D, the library's plane): the mean pressure of the fluid particles within `radius` of
// the node on its minus side minus that on its plus side (each particle's pressure carried
// hydrostatically to the node's height), times the node's share of the length
// (half of each adjacent link), along the plate's normal there (moving_walls.cpp). A side without
// water within the radius counts as p = 0 (the free surface's pressure).
std::vector<Eigen::Vector3d> plate_pressure_loads(const FluidSystem& system,
                                                  const std::vector<Eigen::Vector3d>& nodes,
                                                  double radius);

// Appends wall particles at `positions` (at rest) to a state, for a system built from it that
// resolves a moving solid (FluidSystem::set_moving_walls), and makes room for them in the water:
// fluid particles closer than `clearance` [m] to the polyline through the positions become
// inactive. (A plate set between two lattice columns half a spacing away crowds them to several
// times n0, and the pressure throws them out: a blade standing in still water at t = 0 sent
// particles off at 6 m/s within 6 ms.) Solids given before the water is there clear nothing.
// Distances are straight, not across a periodic seam: a plant within `clearance` of a seam
// leaves the water on the seam's far side in place.
struct AppendedWall {
  std::vector<int> particles;  // indices of the new wall particles, in the order of `positions`
  int cleared = 0;             // fluid particles made inactive
};
AppendedWall append_wall_particles(MpsState& state, const std::vector<Eigen::Vector3d>& positions,
                                   double clearance);

}  // namespace cosim::mps
