// Flexible plants as chains of nodes (seed 000, section 2(2)): axial spring-dashpots, bending
// springs between consecutive links, drag on the normal relative velocity, buoyancy, added mass,
// plant-to-plant contact, and implicit Newmark-beta (beta = 1/4) time integration sub-cycled
// inside a coupling window. No networking here: the process layer feeds ambient velocities in
// and takes positions, velocities and the window-mean drag out.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <concepts>
#include <functional>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "cosim/scenario/parameters.hpp"
#include "cosim/vegetation_beam/banded_matrix.hpp"

namespace cosim::vegetation {

// One plant: a straight, unstressed blade or stem clamped at its base.
struct PlantSpec {
  Eigen::Vector3d base{0, 0, 0};
  Eigen::Vector3d direction{0, 1, 0};  // base to tip, unstressed; normalised on construction
  double length = 0;                   // m
  int links = 20;                      // nodes = links + 1 (node 0 is the clamped base)
  double width = 0;                    // frontal width b, m (drag area and contact size)
  double thickness = 0;                // m
  double bending_stiffness = 0;        // EI, N m^2; if <= 0: youngs_modulus*width*thickness^3/12
  double axial_stiffness = 0;          // EA, N; if <= 0: youngs_modulus*width*thickness
  double youngs_modulus = 0;           // Pa, only used when EI or EA is not given
  double density = 1000;               // plant material sigma, kg/m^3
};

struct BeamParameters {
  double fluid_density = 1000;          // rho, kg/m^3 (0: plant in vacuum)
  double drag_coefficient = 1.0;        // C_D for flow normal to the plant (eq. 16)
  double added_mass_coefficient = 1.0;  // C_M (eq. 8)
  Eigen::Vector3d gravity{0, -9.81, 0};
  double axial_damping_ratio = 0.1;    // alpha_nv of eq. 14, fraction of critical (0: undamped)
  double bending_damping_ratio = 0.1;  // alpha_m of eq. 15, fraction of critical (0: undamped)
  bool contact = true;
  double contact_stiffness = 0;        // N/m; <= 0: the smallest axial link stiffness EA/l0
  double contact_damping_ratio = 0.2;  // fraction of critical for a node pair (and the bed)
  // Bed contact (bed_contact.cpp): a frictionless penalty spring-dashpot keeps the nodes above a
  // plane normal to gravity, bed_below_base under each plant's base; off by default.
  bool bed_contact = false;
  double bed_stiffness = 0;         // N/m per node; <= 0: EA / l0 / max(1, safety_factor)^2
  double bed_below_base = 0;        // m, from the base down to the bed plane
  bool rigid = false;               // nodes never move, drag is still computed
  double safety_factor = 0.5;       // multiplies the spring-mass step limit
  int max_substeps = 100000;        // per window; more throws StabilityError
  double newton_tolerance = 1e-10;  // on the largest position correction, in link lengths
  int max_newton_iterations = 20;   // per attempt; a sub-step makes at most two (see advance)
  // A plant out of contact keeps its factorised Jacobian over the window's later sub-steps of
  // the same length (modified Newton across sub-steps); each window starts with a fresh one.
  bool reuse_jacobian = true;
  // Not a scenario key: a window in which no two plants can touch is solved plant by plant over
  // all its sub-steps (side by side on the threads); false keeps the sub-step-synchronous path
  // for every window (tests compare the two bit for bit).
  bool plants_apart_windows = true;
};

// The keys of one `plants` entry (count and spacing aside), declared once for the parser, the
// library's check (check_plant) and `cosim keys` (cosim/scenario/parameters.hpp).
template <class P, class V>
requires std::same_as<std::remove_const_t<P>, PlantSpec>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  v(Key("base").unit("m").needed().doc("clamped base, world frame"), p.base);
  v(Key("direction").doc("base to tip, unstressed (normalised)"), p.direction);
  v.rule("direction", p.direction.norm() > 0.0, "must not be zero");
  v(Key("length").unit("m").in(Range::positive()).needed().doc("plant length"), p.length);
  v(Key("links").in(Range::between(1, 10000)).doc("nodes = links + 1, node 0 clamped"), p.links);
  v(Key("width").unit("m").in(Range::positive()).needed().doc("frontal width b (drag, contact)"),
    p.width);
  v(Key("thickness").unit("m").in(Range::positive()).needed().doc("thickness"), p.thickness);
  v(Key("density").unit("kg/m^3").in(Range::positive()).needed().doc("plant material sigma"),
    p.density);
  v(Key("bending_stiffness")
        .unit("N m^2")
        .in(Range::non_negative())
        .omitted_means("youngs_modulus width thickness^3 / 12")
        .doc("EI"),
    p.bending_stiffness);
  v(Key("axial_stiffness")
        .unit("N")
        .in(Range::non_negative())
        .omitted_means("youngs_modulus width thickness")
        .doc("EA"),
    p.axial_stiffness);
  const bool derived = !(p.bending_stiffness > 0) || !(p.axial_stiffness > 0);
  v(Key("youngs_modulus")
        .unit("Pa")
        .in(Range::positive())
        .needed()
        .only_with(derived, "bending_stiffness or axial_stiffness not given")
        .doc("E, for the stiffnesses not given"),
    p.youngs_modulus);
  // E b t^3 / 12 of a very thin plant can underflow to 0 (t = 1e-110 m: t^3 = 0).
  const double ei = p.bending_stiffness > 0
                        ? p.bending_stiffness
                        : p.youngs_modulus * p.width * std::pow(p.thickness, 3) / 12;
  const double ea =
      p.axial_stiffness > 0 ? p.axial_stiffness : p.youngs_modulus * p.width * p.thickness;
  v.rule("youngs_modulus", ei > 0 && ea > 0 && std::isfinite(ei) && std::isfinite(ea),
         "the stiffness from youngs_modulus, width and thickness is not a positive finite number: "
         "give bending_stiffness and axial_stiffness");
}

// A plant as the scenario reads it when keys are absent: in the world frame, standing along +z.
inline PlantSpec scenario_plant_defaults() {
  PlantSpec spec;
  spec.direction = Eigen::Vector3d::UnitZ();
  return spec;
}

// The keys of `participants.vegetation_beam` that are BeamParameters (gravity is the scene's).
template <class P, class V>
requires std::same_as<std::remove_const_t<P>, BeamParameters>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  v(Key("fluid_density").unit("kg/m^3").in(Range::non_negative()).doc("rho (0: vacuum)"),
    p.fluid_density);
  v(Key("drag_coefficient").in(Range::non_negative()).doc("C_D, flow normal to the plant"),
    p.drag_coefficient);
  v(Key("added_mass_coefficient").in(Range::non_negative()).doc("C_M"), p.added_mass_coefficient);
  v(Key("axial_damping_ratio").in(Range::between(0.0, 10.0)).doc("fraction of critical"),
    p.axial_damping_ratio);
  v(Key("bending_damping_ratio").in(Range::between(0.0, 10.0)).doc("fraction of critical"),
    p.bending_damping_ratio);
  v(Key("contact").doc("plant-to-plant contact"), p.contact);
  v(Key("contact_stiffness").unit("N/m").in(Range::non_negative()).doc("0: the smallest EA / l0"),
    p.contact_stiffness);
  v(Key("bed_contact").doc("nodes stay above the bed plane (penalty spring-dashpot)"),
    p.bed_contact);
  v(Key("bed_stiffness")
        .unit("N/m")
        .in(Range::non_negative())
        .only_with(p.bed_contact, "bed_contact: true")
        .doc("per node; 0: EA / l0 / max(1, safety_factor)^2 (resolved by the sub-step)"),
    p.bed_stiffness);
  v(Key("bed_below_base")
        .unit("m")
        .in(Range::non_negative())
        .only_with(p.bed_contact, "bed_contact: true")
        .doc("bed plane (normal to gravity) this far below each base"),
    p.bed_below_base);
  v(Key("rigid").doc("nodes never move; drag is still computed"), p.rigid);
  // Newmark average acceleration is unconditionally stable: factors above 1 trade axial-strain
  // accuracy for speed (seed 000: 10 to 100 beam steps per fluid step suffice).
  v(Key("safety_factor").in(Range{0.0, 1000.0, true}).doc("multiplies the spring-mass step"),
    p.safety_factor);
  v(Key("max_substeps").in(Range::between(1, 100000000)).doc("per window; more is an error"),
    p.max_substeps);
  // Looser than 1e-3 of a link per sub-step is no longer small against the shapes to resolve.
  v(Key("newton_tolerance").in(Range{0.0, 1e-3, true}).doc("largest correction / link length"),
    p.newton_tolerance);
  v(Key("max_newton_iterations").in(Range::between(1, 1000)).doc("per attempt of a sub-step"),
    p.max_newton_iterations);
  v(Key("reuse_jacobian").doc("keep each plant's Newton Jacobian over a window's sub-steps"),
    p.reuse_jacobian);
}

// Library checks (the declared ranges and rules); throw scenario::ParameterError naming the key.
inline void check_plant(const PlantSpec& spec, int index) {
  scenario::check_parameters(spec, "vegetation_beam: plant " + std::to_string(index));
}
inline void check_beam_parameters(const BeamParameters& p) {
  scenario::check_parameters(p, "vegetation_beam");
  if (!(p.contact_damping_ratio >= 0))  // not a scenario key
    throw scenario::ParameterError("vegetation_beam", "contact_damping_ratio", "must be >= 0");
}

// Rough memory of a plant field [bytes]: the per-node arrays of PlantField (about 30
// three-vectors and scalars, two 3x3 contact blocks, the banded Jacobian) measured 1.04 kB per
// node (RSS after a window, 2000 plants x 100 links); the process adds its link buffers and
// output frames (about 20 more three-vectors per node).
inline constexpr double kBytesPerPlantNode = 1600.0;
inline constexpr double kBytesPerPlant = 600.0;  // specs, per-plant constants, pairs
inline double estimated_memory_bytes(double plants, double nodes) {
  return plants * kBytesPerPlant + nodes * kBytesPerPlantNode;
}

struct WindowReport {
  int substeps = 0;
  double substep = 0;
  int max_newton_iterations = 0;   // largest Newton iteration count of any sub-step (both tries)
  int newton_restarts = 0;         // times the robust Newton attempt took over in the window
  int cutbacks = 0;                // sub-steps halved because both Newton attempts failed
  int factorizations = 0;          // plant Jacobians factorised (one per plant and sub-step
                                   // without reuse_jacobian)
  int most_plants_in_contact = 0;  // in any sub-step (they are solved one after another)
  bool plants_apart = false;       // solved plant by plant over the whole window (advance())
};

// A linear vibration mode of one plant about its current shape.
struct LinearMode {
  double frequency = 0;                // Hz
  std::vector<Eigen::Vector3d> shape;  // per node of the plant, base first (zero); x^T M x = 1
};

struct StaticReport {
  int iterations = 0;
  double max_correction = 0;  // last Newton correction, m
};

// Raised on NaN, runaway energy, an escaping node or a step limit; the message names the plant,
// node, quantity and limit.
class StabilityError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class PlantField {
 public:
  PlantField(std::vector<PlantSpec> plants, BeamParameters parameters);

  int plant_count() const { return static_cast<int>(plants_.size()); }
  int node_count() const { return static_cast<int>(positions_.size()); }
  std::pair<int, int> node_range(int plant) const;  // [first, last + 1), base node first
  const std::vector<PlantSpec>& specs() const { return specs_; }
  const BeamParameters& parameters() const { return parameters_; }

  const std::vector<Eigen::Vector3d>& positions() const { return positions_; }
  const std::vector<Eigen::Vector3d>& velocities() const { return velocities_; }
  double time() const { return time_; }

  // Largest sub-step from the axial (l0 sqrt(m/EA/l0)) and bending ((l0^2/2) sqrt(m/EI))
  // spring-mass periods with added mass, and the contact spring, times safety_factor.
  double stable_substep() const;
  // ceil(window_dt / stable_substep()); throws StabilityError if above max_substeps.
  int substeps_for(double window_dt) const;

  // Advances one coupling window. Ambient fluid velocity per node (all nodes) at the window's
  // start and end, interpolated linearly across the sub-steps. Each sub-step is solved by
  // modified Newton from the constant-acceleration predictor (fast). If that does not converge
  // within max_newton_iterations, the sub-step is solved again by the robust attempt: the
  // constant-velocity predictor, the drag's tangent terms in the Jacobian, and the Jacobian
  // refreshed whenever an iteration fails to quarter the correction (needed far above the
  // spring-mass limit, e.g. after a load step at t = 0); the rest of the window starts with it.
  // If both fail, the sub-step is halved (up to 6 times); then StabilityError names the plant
  // and node with the largest residual and what to change.
  WindowReport advance(double window_dt, const std::vector<Eigen::Vector3d>& ambient_begin,
                       const std::vector<Eigen::Vector3d>& ambient_end);
  // Per node: force the fluid exerted on the plant (drag), averaged over the last window. The
  // fluid must take minus this; the average is the Newmark (trapezoidal) impulse / window_dt, so
  // momentum exchanged with the fluid matches the plant's momentum change exactly.
  const std::vector<Eigen::Vector3d>& window_mean_drag() const { return window_mean_drag_; }

  // Constant extra force per node (all nodes; base entries are ignored), e.g. a tip load.
  void set_external_forces(std::vector<Eigen::Vector3d> forces);
  const std::vector<Eigen::Vector3d>& external_forces() const { return external_forces_; }
  // Per node, the submerged share in [0, 1] (from the fluid's samples): drag and buoyancy act
  // on that share; the default is fully submerged. Added mass is kept (it sets the step).
  void set_water_fraction(const std::vector<double>& fraction);
  // Replaces the state (e.g. an initial deflection); accelerations are recomputed lazily.
  void set_state(std::vector<Eigen::Vector3d> positions, std::vector<Eigen::Vector3d> velocities);

  // Static equilibrium of elastic, contact, gravity-buoyancy and external forces (no fluid) by
  // Newton's method from the current shape; velocities are set to zero. Tolerance on the largest
  // correction in link lengths; StabilityError names the node with the largest residual.
  StaticReport solve_static(double tolerance = 1e-12, int max_iterations = 100);

  double kinetic_energy() const;    // includes the added fluid mass (eq. 8)
  double elastic_energy() const;    // axial, bending and contact springs
  double potential_energy() const;  // gravity minus buoyancy and external forces, 0 at start
  Eigen::Vector3d tip_displacement(int plant) const;
  // Lowest `count` distinct frequencies (Hz) of the plant linearised about its current shape,
  // from K x = omega^2 M x (Eigen's generalized self-adjoint solver). The two bending planes of
  // a straight plant are degenerate and reported once.
  std::vector<double> linear_natural_frequencies(int plant, int count) const;
  // The lowest `count` modes (degenerate pairs listed one by one), from the same problem.
  std::vector<LinearMode> linear_modes(int plant, int count) const;
  // Sets the plant's velocities to its linear mode `mode` (1-based, counted as in
  // linear_natural_frequencies), combining a degenerate pair so that the tip velocity comes as
  // close to `tip_velocity` (m/s) as the mode allows (least squares). Returns the tip velocity
  // set; positions are kept.
  Eigen::Vector3d set_mode_velocity(int plant, int mode, const Eigen::Vector3d& tip_velocity);

 private:
  // Reads and writes the evolving state (checkpoint.cpp); the rest is rebuilt from the specs.
  friend struct PlantFieldCheckpoint;

  // Per-plant constants derived from PlantSpec and BeamParameters (eq. 12-15).
  struct Plant {
    int first = 0;              // global index of the base node
    int links = 0;              // free nodes are first+1 .. first+links
    double link_length = 0;     // l0
    double axial_spring = 0;    // k_nv = EA / l0 (eq. 12)
    double axial_damper = 0;    // c_nv (eq. 14)
    double bending_spring = 0;  // joint moment per angle EI / l0 (= k_m l0^2 of eq. 13)
    double bending_damper = 0;  // joint moment per relative angular velocity (eq. 15)
    double drag_factor = 0;     // 0.5 rho C_D b, multiplied by the node's length share
    double contact_radius = 0;  // half the width
    Eigen::Vector3d ghost;      // fixed node mirrored below the base: clamps the rotation
    double speed_limit = 0;     // faster nodes mean runaway energy
    // Bed contact: a node is in contact while bed_normal . x < bed_height (the bed plane plus
    // half the thickness); bed_spring 0 means no bed contact.
    Eigen::Vector3d bed_normal{0, 0, 1};
    double bed_height = 0, bed_spring = 0, bed_damper = 0;
    double reach_limit = 0;  // nodes farther from the base have escaped
  };

  // Outcome of one Newton attempt of a sub-step; on failure the plant and node (local index)
  // with the largest residual |m a - F| (N), or where the correction or a pivot failed.
  struct NewtonOutcome {
    bool converged = false;
    int iterations = 0;
    int factorizations = 0;  // plant Jacobians factorised in the attempt
    int plants_in_contact = 0;
    std::string failure;  // what went wrong, empty if converged
    int plant = 0, node = 0;
    double residual = 0;    // N, at that node
    double correction = 0;  // last largest correction of that plant, in link lengths
  };
  // Largest correction of one Newton update, in link lengths, and its node (local index); a
  // non-finite correction gives an infinite `largest`, a failed pivot sets `singular`.
  struct Correction {
    double largest = 0;
    int node = 1;
    bool singular = false;
  };

  std::pair<double, std::string> step_limit() const;  // stable step and what limits it
  void initialise_accelerations(const std::vector<Eigen::Vector3d>& ambient);
  // One implicit Newmark sub-step of length dt from t0 with the ambient flow at its start and
  // end (halves itself when both Newton attempts fail); adds its drag impulse to `impulse`.
  void substep(double t0, double dt, const std::vector<Eigen::Vector3d>& ambient_start,
               const std::vector<Eigen::Vector3d>& ambient_end, int depth,
               std::vector<Eigen::Vector3d>& impulse, WindowReport& report);
  // One Newton attempt from the state in previous_*: constant-acceleration predictor with the
  // Jacobian of the first iteration kept (fast), or constant-velocity predictor with the
  // Jacobian refreshed when the correction falls by less than a factor 4 (robust).
  // Accelerations and velocities of every free node from its trial position (Newmark, seed eq.
  // 22-23; mass_weight = 1 / (beta dt^2)); the clamped bases at rest.
  void newmark_kinematics(double dt, double mass_weight);
  NewtonOutcome newton_attempt(double dt, const std::vector<Eigen::Vector3d>& ambient, bool robust);
  // What one Newton iteration over the plants needs to know.
  struct NewtonSweep {
    double dt = 0, mass_weight = 0, damping_weight = 0;
    int iteration = 1;
    bool robust = false, contact = false;
    bool reuse = false;  // a plant's Jacobian kept from an earlier sub-step of this dt may serve
    const std::vector<Eigen::Vector3d>* ambient = nullptr;
  };
  // Per plant, over the iterations of one attempt.
  struct NewtonProgress {
    std::vector<char> converged, refresh;
    std::vector<char> kept;  // the plant solves with a Jacobian kept from an earlier sub-step
    std::vector<double> last_correction;
    std::vector<Correction> corrections;  // of the current iteration
  };
  // Returns whether it factorised the plant's Jacobian.
  bool newton_iteration(int plant, const NewtonSweep& sweep, NewtonProgress& progress,
                        std::vector<double>& scratch);
  // One iteration over all plants; returns the lowest failing plant, or plant_count(), and adds
  // the Jacobians it factorised to `factorizations`.
  int newton_sweep(const NewtonSweep& sweep, NewtonProgress& progress, int& factorizations);
  // Plant and node with the largest residual among the plants not `converged`.
  void locate_largest_residual(const std::vector<char>& converged, NewtonOutcome& outcome) const;
  void check_state(const std::vector<Eigen::Vector3d>& ambient) const;
  // Plant-to-plant contact is on and there are plants to touch.
  bool plants_may_touch() const { return parameters_.contact && plant_count() > 1; }
  // The largest distance a node of x lies from its place in `from` [m].
  static double largest_move(std::span<const Eigen::Vector3d> x,
                             const std::vector<Eigen::Vector3d>& from);
  // What check_state would throw for plant p, or empty.
  std::string state_problem(int plant, const std::vector<Eigen::Vector3d>& ambient) const;
  void newmark_kinematics_of(const Plant& plant, double dt, double mass_weight);
  // Plants apart (plant_field_apart.cpp): whether no two plants can touch while every node stays
  // within a quarter of clearance_margin_ of where this was last checked.
  bool plants_clear();
  // The window plant by plant; false (the state then as at the window's start) when a plant's
  // fast Newton attempt fails, its state check fails or a node drifts too far to rule out a
  // contact: advance() then solves the window sub-step by sub-step.
  bool advance_plants_apart(const std::vector<Eigen::Vector3d>& ambient_begin,
                            const std::vector<Eigen::Vector3d>& ambient_end,
                            std::vector<Eigen::Vector3d>& impulse, WindowReport& report);
  struct ApartWindow;  // what the plants of an apart window share (plant_field_apart.cpp)
  // One plant over the window; false when its fast attempt or its state check fails, or a node
  // drifts too far from clearance_positions_.
  bool advance_plant_apart(int plant, const ApartWindow& window, std::vector<double>& scratch);
  // The contact bookkeeping the sub-step-synchronous path would leave after the apart window:
  // its candidate updates at each sub-step's start, and no pair active.
  void settle_contact_state(int substeps);
  void clear_contact_forces();  // no contact force, no plant in contact
  void clear_contact_state();   // the same, and no pair active
  // visit(a, b) for each node pair of different plants (not two clamped bases) closer than
  // their contact radii plus `margin` at x, a < b in node order; stops when visit returns false.
  void for_each_close_pair(const std::vector<Eigen::Vector3d>& x, double margin,
                           const std::function<bool(int, int)>& visit) const;
  void update_contact_candidates();
  void update_contact_candidates(std::span<const Eigen::Vector3d> x);
  void compute_contact_forces(const std::vector<Eigen::Vector3d>& x,
                              const std::vector<Eigen::Vector3d>& v, bool decide_active_pairs);
  // Recomputes the contact forces on one plant's nodes from its active pairs at the current
  // trial positions (Gauss-Seidel update inside the Newton loop of a sub-step of length dt).
  void refresh_contact_forces(int plant, double dt);
  // Sum of forces on the plant's nodes into `force` (base entry unused) and the drag part into
  // `drag` (base included). With a Jacobian: adds stiffness_weight * K + damping_weight * C
  // over the free nodes (local node i-1 for global node first+i); drag_stiffness adds the
  // drag's dependence on the node positions through the tangent to K.
  void compute_forces(int plant, const std::vector<Eigen::Vector3d>& x,
                      const std::vector<Eigen::Vector3d>& v,
                      const std::vector<Eigen::Vector3d>& ambient, bool include_contact,
                      std::vector<Eigen::Vector3d>& force, std::vector<Eigen::Vector3d>& drag,
                      BandedMatrix* jacobian, double stiffness_weight, double damping_weight,
                      bool drag_stiffness = false) const;
  // Adds the bed's normal force on the plant's free nodes (bed_contact.cpp) to `force`, and its
  // stiffness and damping to the Jacobian, for the nodes below the bed at x.
  void add_bed_contact(const Plant& plant, const std::vector<Eigen::Vector3d>& x,
                       const std::vector<Eigen::Vector3d>& v, std::vector<Eigen::Vector3d>& force,
                       BandedMatrix* jacobian, double stiffness_weight,
                       double damping_weight) const;
  void setup_bed_contact(Plant& plant, const PlantSpec& spec, double link_mass) const;
  double bed_energy() const;  // of the bed springs at the current positions
  // Solves jacobian * correction = -residual for one plant (factorising first if asked) and
  // applies it (not when the factorisation fails); `correction` is scratch (one per thread).
  Correction apply_newton_correction(int plant, BandedMatrix& jacobian,
                                     const std::vector<Eigen::Vector3d>& residual, bool factorize,
                                     std::vector<double>& correction);
  // The symmetric stiffness and the lumped mass of one plant about its current shape.
  void linear_problem(int plant, Eigen::MatrixXd& stiffness, Eigen::MatrixXd& mass) const;

  std::vector<PlantSpec> specs_;
  BeamParameters parameters_;
  std::vector<Plant> plants_;
  std::vector<Eigen::Vector3d> positions_, velocities_, accelerations_;
  std::vector<Eigen::Vector3d> initial_positions_;
  std::vector<Eigen::Vector3d> external_forces_, body_forces_;  // body: gravity minus buoyancy
  std::vector<Eigen::Vector3d> plant_weight_, displaced_weight_;
  std::vector<double> water_fraction_;  // per node, 1 submerged (drag and buoyancy act)
  std::vector<double> node_mass_, contact_radius_;
  std::vector<int> node_plant_;
  std::vector<Eigen::Vector3d> window_mean_drag_;
  // Scratch of the sub-step (kept to avoid reallocation).
  std::vector<Eigen::Vector3d> previous_positions_, previous_velocities_, previous_accelerations_;
  std::vector<Eigen::Vector3d> previous_drag_;
  bool robust_first_ = false;  // the fast Newton attempt failed earlier in this window
  std::vector<Eigen::Vector3d> forces_, drag_, residual_;
  std::vector<std::vector<double>> newton_scratch_;  // per thread: one plant's correction
  std::vector<BandedMatrix> jacobians_;  // per plant, factorised at a sub-step's first iteration
  // Per plant: the sub-step length its factorised Jacobian was built for, 0 when it may not be
  // kept (none yet, a new window, built in contact or in a robust attempt, or it failed).
  std::vector<double> jacobian_dt_;
  // Contact: candidate node pairs within reach plus a margin, rebuilt when nodes moved.
  std::vector<std::pair<int, int>> contact_candidates_;
  std::vector<char> contact_active_;                   // per candidate, fixed during a sub-step
  std::vector<std::vector<int>> plant_contact_pairs_;  // active candidate indices per plant
  std::vector<Eigen::Vector3d> candidate_positions_;
  std::vector<Eigen::Vector3d> contact_forces_;
  std::vector<Eigen::Matrix3d> contact_stiffness_blocks_, contact_damping_blocks_;
  std::vector<int> contact_touched_nodes_;
  std::vector<char> plant_in_contact_;
  double contact_stiffness_ = 0, contact_damping_ = 0, contact_margin_ = 0;
  bool candidates_valid_ = false;
  // Plants apart: positions of the last clearance check, its margin and outcome; the window's
  // start state (restored when an apart window falls back) and its sub-steps' start positions.
  std::vector<Eigen::Vector3d> clearance_positions_;
  double clearance_margin_ = 0;
  bool clearance_valid_ = false, plants_clear_ = false;
  bool last_window_robust_ = false;  // the last window needed the robust attempt
  std::vector<Eigen::Vector3d> start_positions_, start_velocities_, start_accelerations_;
  std::vector<Eigen::Vector3d> start_drag_, substep_starts_;
  bool accelerations_valid_ = false;
  double time_ = 0;
};

}  // namespace cosim::vegetation
