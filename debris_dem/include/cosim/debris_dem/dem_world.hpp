// Three-dimensional DEM of boulders (spheres), logs and dam columns (flat-ended cylinders) and
// flume walls (fixed triangles) after seed 004 (Shibuya, Haraki, Katsuki). Physics only: no
// networking. The caller supplies the ambient water velocity and water fraction per moving
// element each coupling window; the world sub-cycles and reports the mean fluid force.
#pragma once

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "cosim/debris_dem/contact_law.hpp"

namespace cosim::dem {

// Thrown on NaN, excessive overlap or escape from the domain; the message names the element
// and the quantity so the coupler can report it with the window.
class StabilityError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Contact spring parameters are per element material; a pair uses the mean of its two
// materials (identical materials give exactly the table 3 values of seed 004).
struct Material {
  double density = 1900.0;              // kg/m^3 (seed 004 table 3: spheres 1.9, logs 0.8)
  double normal_stiffness = 1.0e4;      // K_n, N/m (seed 004 table 3)
  double tangential_stiffness = 4.0e3;  // K_s, N/m (seed 004 table 3)
  // Damping ratio h of the normal and tangential dashpots (seed 004 table 3: h = 0.2). If
  // restitution > 0 it overrides: the damping ratio that gives this head-on e under the normal
  // law in use (damping_ratio_for_restitution in contact_law.hpp), so e is what is asked whether
  // or not the normal force is clipped.
  double damping_ratio = 0.2;
  double restitution = 0.0;
  double friction = 0.404;  // tan(phi) of the Mohr-Coulomb limit, cohesion c = 0 (table 3)

  // clipped: DemParameters::clip_normal_force of the world the material is used in.
  [[nodiscard]] double effective_damping_ratio(bool clipped) const;
};

// Drag on an element in the fluid (dem_fluid.cpp).
enum class DragLaw : std::uint8_t {
  // Seed 004 eq. (48): constant C_D (drag_coefficient_sphere / _cylinder) on the projected area.
  kSeed004,
  // Spheres: Schiller & Naumann (1933) C_D(Re), Re on the diameter. Logs: the crossflow
  // (independence) principle, Hoerner, Fluid-Dynamic Drag (1965): the velocity component
  // normal to the axis drives C_D(Re_n) of a circular cylinder (White's fit) on D L, the axial
  // component the sphere C_D(Re_t) of the log's diameter on the end area pi r^2 (end-on flow
  // past a blunt body; logs in a stream mostly see crossflow).
  kSchillerNaumann,
};

struct DemParameters {
  // Gravity in the world frame; slope_gravity() in scenes.hpp tilts it for a flume frame.
  Eigen::Vector3d gravity{0.0, 0.0, -9.81};
  double fluid_density = 1000.0;
  double drag_coefficient_sphere = 0.49;  // seed 004 section 4.1(3), from Hashimoto et al.
  // Seed 004 gives a log the drag of a sphere of equal projected area; here the area normal to
  // the relative flow, 2 r L sin + pi r^2 cos, is used with this coefficient.
  double drag_coefficient_cylinder = 0.49;
  // The unresolved CFD-DEM force set (Zhou, Kuang, Chu & Yu, J. Fluid Mech. 661 (2010) 482-510):
  // drag, pressure gradient and added mass, all on the submerged volume V_sub. The defaults
  // keep seed 004's drag and buoyancy alone.
  DragLaw drag_law = DragLaw::kSeed004;
  double fluid_viscosity = 1.0e-3;  // mu, Pa s (water at 20 C), for the Reynolds numbers
  // Multiply the drag by eps^(2 - chi) of Di Felice (1994), eps the local fluid volume fraction
  // local_voidage() estimates from the moving elements within voidage_radius (m, several
  // element diameters), updated once per window (elements move far less than the radius in
  // one). Needs kSchillerNaumann.
  bool voidage_correction = false;
  double voidage_radius = 0.0;
  // Pressure-gradient force -V_sub grad p with grad p = rho_f (g - Du/Dt): besides buoyancy
  // -rho_f V_sub g it adds rho_f V_sub Du/Dt (the fluid's acceleration at the element).
  bool fluid_acceleration_force = false;
  // Added mass rho_f V_sub C (Du/Dt - dv/dt), integrated implicitly (the element's inertia
  // becomes m + rho_f V_sub C), so light elements stay stable. C = C_a for spheres (0.5, potential
  // flow: Lamb, Hydrodynamics, 6th ed. (1932)); for logs the tensor C_n (I - a a^T) + C_t a a^T:
  // C_n = 1 of a circular cylinder per unit length and C_t ~ 0 along a slender body (Newman,
  // Marine Hydrodynamics (1977) ch. 4; Brennen, A review of added mass and fluid inertial forces,
  // NCEL CR 82.010 (1982)). The contact dashpots keep the solid mass (pair_constants).
  bool added_mass = false;
  double added_mass_sphere = 0.5;
  double added_mass_cylinder_normal = 1.0;
  double added_mass_cylinder_axial = 0.0;
  double list_margin = 5.0e-3;  // r_dam of table 3: extra reach of candidate lists
  // t_reset of table 3 (s): seed 004 rebuilds its lists every 1e-3 s. Infinity (the default):
  // no fixed interval, the list is rebuilt only when two elements may have closed the margin
  // (list_sweep_guard), the half-skin rule of a Verlet list (Allen & Tildesley, Computer
  // Simulation of Liquids (1987) 5.3). Results do not depend on it while the guard is on (a list
  // that holds every pair within the margin gives the same forces in the same order); in the
  // settling benchmark it cuts rebuilds from 40 to about 10 per 4000 steps.
  double list_reset_interval = std::numeric_limits<double>::infinity();
  // Also rebuild the list as soon as two elements may have closed the margin (translation plus a
  // log's end sweep); false keeps only the fixed interval of the seed.
  bool list_sweep_guard = true;
  // OpenMP threads for contacts, integration and lists. 1 by default: in a co-simulation the
  // solvers already share the cores, and an oversubscribed barrier costs more than it saves.
  int threads = 1;
  double safety_factor = 0.1;      // dt = safety_factor * sqrt(m_min / k_max)
  double user_dt = 0.0;            // > 0 forces this sub-step (seed 004: 1e-5 s)
  double max_overlap_ratio = 0.5;  // overlap / smaller radius that stops the run
  double region_size = 1.0;        // local-origin cell size, section 2.4(10) (m)
  // true: total normal force (spring + dashpot) is clipped at zero, no tension (seed 004
  // fig. 3a). false: the dashpot may pull while overlapping, matching the closed form of e.
  bool clip_normal_force = true;
  Eigen::Vector3d domain_min = Eigen::Vector3d::Constant(-1.0e6);
  Eigen::Vector3d domain_max = Eigen::Vector3d::Constant(1.0e6);
};

enum class ElementKind : std::uint8_t { kSphere, kCylinder, kTriangle };

// The fluid at the moving elements over one window, one entry per moving element (order of
// moving_elements()). Empty velocity: no fluid at all.
struct FluidAtElements {
  std::vector<Eigen::Vector3d> velocity;      // ambient fluid velocity u_f, m/s
  std::vector<Eigen::Vector3d> acceleration;  // Du/Dt of the fluid, m/s^2; empty = 0
  // World z of the free surface above the element; NaN (or empty) = use water_fraction;
  // -inf = no water above (dry).
  std::vector<double> surface_elevation;
  // Submerged share 0..1; needed for every element without a finite surface_elevation.
  std::vector<double> water_fraction;
};

struct WindowReport {
  int substeps = 0;
  double substep = 0.0;
  int contacts = 0;  // touching pairs after the last sub-step
  double max_overlap_ratio = 0.0;
};

class DemWorld {
 public:
  explicit DemWorld(DemParameters parameters = {});
  ~DemWorld();
  DemWorld(const DemWorld&) = delete;
  DemWorld& operator=(const DemWorld&) = delete;
  DemWorld(DemWorld&&) noexcept;
  DemWorld& operator=(DemWorld&&) noexcept;

  int add_sphere(const Eigen::Vector3d& center, double radius, const Material& material,
                 bool fixed = false);
  // length is the full length; the cylinder spans center +- 0.5 length axis_unit.
  int add_cylinder(const Eigen::Vector3d& center, const Eigen::Vector3d& axis_unit, double radius,
                   double length, const Material& material, bool fixed = false);
  // Triangles are fixed and two-sided. Triangles of one mesh may share edges and vertices: the
  // contacts of an element with several triangles are filtered so that one surface gives one
  // contact (see compute_forces).
  int add_triangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                   const Material& material);
  // A removable gate: the quadrilateral p0-p1-p2-p3 as two triangles (seed 004 section 4.1(1):
  // the packing is held by triangles that are removed to release the debris).
  int add_gate(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& p2,
               const Eigen::Vector3d& p3, const Material& material);
  void set_gate_active(bool active);
  [[nodiscard]] bool gate_active() const { return gate_active_; }

  [[nodiscard]] int element_count() const;
  [[nodiscard]] ElementKind kind(int element) const;
  [[nodiscard]] bool is_fixed(int element) const;
  [[nodiscard]] Eigen::Vector3d position(int element) const;  // center (triangle: vertex a)
  [[nodiscard]] Eigen::Vector3d velocity(int element) const;
  [[nodiscard]] Eigen::Vector3d angular_velocity(int element) const;  // world frame
  [[nodiscard]] Eigen::Quaterniond orientation(int element) const;    // body -> world
  [[nodiscard]] Eigen::Vector3d axis(int element) const;              // cylinder axis (world)
  [[nodiscard]] double radius(int element) const;
  [[nodiscard]] double length(int element) const;  // cylinder full length, else 0
  [[nodiscard]] double mass(int element) const;
  [[nodiscard]] double volume(int element) const;
  [[nodiscard]] std::vector<Eigen::Vector3d> triangle_vertices(int element) const;

  void set_velocity(int element, const Eigen::Vector3d& velocity);
  void set_angular_velocity(int element, const Eigen::Vector3d& omega_world);

  // Moving elements in element order: index k of element_centers(), advance() inputs and
  // window_mean_fluid_force() is moving_elements()[k].
  [[nodiscard]] const std::vector<int>& moving_elements() const { return moving_; }
  [[nodiscard]] std::vector<Eigen::Vector3d> element_centers() const;
  [[nodiscard]] std::vector<Eigen::Vector3d> element_velocities() const;

  [[nodiscard]] double stable_dt() const;
  // Sub-cycles window_dt with the fluid held over the window (dem_fluid.cpp).
  WindowReport advance(double window_dt, const FluidAtElements& fluid);
  // Seed 004 inputs: ambient velocity and water fraction per moving element (empty: no fluid).
  WindowReport advance(double window_dt, const std::vector<Eigen::Vector3d>& ambient_velocity,
                       const std::vector<double>& water_fraction);
  // One sub-step of dt without fluid (tests, packing).
  void step(double dt);
  // Window-mean total force the fluid exerted on each moving element (drag, pressure gradient
  // with buoyancy, added mass): the fluid takes exactly minus it.
  [[nodiscard]] const std::vector<Eigen::Vector3d>& window_mean_fluid_force() const {
    return mean_fluid_force_;
  }
  // The part of it the fluid takes back: drag and added mass, window mean [N]. The pressure-
  // gradient force (buoyancy, -V grad p) is the fluid's own pressure on the volume the element
  // occupies; the unresolved fluid still fills that volume (no voidage in its equations), so
  // its pressure already carries it, and feeding it back would count it twice (a floating log
  // then sinks, pushing its share of fluid down with it). Zhou et al., J. Fluid Mech. 661 (2010)
  // 482-510, model B: the fluid-particle coupling term excludes the pressure-gradient force.
  [[nodiscard]] const std::vector<Eigen::Vector3d>& window_mean_interaction_force() const {
    return mean_interaction_force_;
  }
  // Submerged share of each moving element at the last sub-step (0 without fluid).
  [[nodiscard]] const std::vector<double>& submerged_fraction() const {
    return submerged_fraction_;
  }
  // Local fluid volume fraction of each moving element the last window used (1 without the
  // voidage correction).
  [[nodiscard]] const std::vector<double>& voidage() const { return voidage_; }

  [[nodiscard]] double kinetic_energy() const;
  [[nodiscard]] double potential_energy() const;  // m g . x relative to the world origin
  [[nodiscard]] double elastic_energy() const;    // stored in the contact springs
  [[nodiscard]] double time() const { return time_; }
  [[nodiscard]] long long step_count() const { return step_count_; }
  [[nodiscard]] int contact_count() const;
  [[nodiscard]] long long list_rebuilds() const { return list_rebuilds_; }
  [[nodiscard]] const DemParameters& parameters() const { return parameters_; }
  DemParameters& mutable_parameters() { return parameters_; }

  // Internal layout, public for the candidate list and contact kernels in src/.
  // Line-aligned, with what the contact loop reads of the other element of a pair (position,
  // radius, velocities) in the first 128 bytes: 5000 elements are 1.9 MB and share the core's
  // L2 with the pair lists, so a pair costs one or two cache lines of element B, not four.
  struct alignas(64) Element {
    ElementKind kind = ElementKind::kSphere;
    bool fixed = false;
    bool enabled = true;  // false for a removed gate
    int gate = -1;        // gate id of a gate triangle
    Eigen::Vector3i cell =
        Eigen::Vector3i::Zero();  // local origin B^m = cell * region_size (seed 004 eq. 45)
    double radius = 0.0;
    Eigen::Vector3d local = Eigen::Vector3d::Zero();
    Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
    Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();  // world frame
    double inverse_mass = 0.0;
    Eigen::Vector3d angular_momentum = Eigen::Vector3d::Zero();  // world frame
    Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
    Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  // cylinder axis, world frame
    double half_length = 0.0;
    double mass = 0.0;
    Eigen::Vector3d inertia_body = Eigen::Vector3d::Zero();  // principal, body z = axis
    double bounding_radius = 0.0;
    double sweep = 0.0;  // bound on surface-point travel since the last list build
    int material = 0;
    // Triangle geometry relative to vertex a (the anchor).
    Eigen::Vector3d edge1 = Eigen::Vector3d::Zero();
    Eigen::Vector3d edge2 = Eigen::Vector3d::Zero();
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  };
  struct PairSlot {
    int a = -1;
    int b = -1;
    double reach = 0.0;  // radius_a + radius_b (m): a sphere pair farther apart is not touching
    PairKind kind = PairKind::kSphereSphere;
    bool touching = false;
  };
  struct PairState {
    PairConstants constants{};
    Eigen::Vector3d tangential_spring = Eigen::Vector3d::Zero();
    double overlap = 0.0;
    double overlap_ratio = 0.0;
  };
  // Compact copies, in element order, of what the contact loops read of the elements of a pair
  // (written by integrate(), refreshed from elements_ when a setter made them stale): 5000
  // elements are 240 kB each (48 bytes an element, 1.9 MB as Element), so element B stays in
  // L2 (the loop was bound by misses on it). Identical values, so the forces are bitwise
  // unchanged.
  struct HotPosition {
    Eigen::Vector3d local;  // m, from the local origin cell * region_size
    double radius;          // m
    Eigen::Vector3i cell;
    int padding;
  };
  struct HotVelocity {
    Eigen::Vector3d velocity;          // m/s
    Eigen::Vector3d angular_velocity;  // rad/s, world frame
  };
  struct PairResult {
    Eigen::Vector3d force_on_a;
    Eigen::Vector3d lever_a;
    Eigen::Vector3d lever_b;
  };
  // Candidate k as the contact law sees it (no force or levers yet).
  [[nodiscard]] ContactPair candidate_pair(int k) const;
  [[nodiscard]] const std::vector<Element>& elements() const { return elements_; }
  [[nodiscard]] const std::vector<Material>& materials() const { return materials_; }
  // Material m's dashpot damping ratio under the normal law in use (solved once per material).
  [[nodiscard]] double damping_ratio(int material) const;
  // Displacement from element b's anchor to element a's anchor via local origins (eq. 45-46).
  [[nodiscard]] Eigen::Vector3d displacement(int a, int b) const;

 private:
  int add_element(Element element, const Eigen::Vector3d& anchor, const Material& material);
  int material_index(const Material& material);
  void compute_forces(double dt);
  // with_fluid: use the added mass and fluid acceleration apply_fluid() left for this sub-step.
  // Returns whether an element may fail check_stability() (a value not finite or a position
  // outside the domain), tested on the values just computed; only then is the check run.
  [[nodiscard]] bool integrate(double dt, bool with_fluid);
  void check_stability() const;
  void update_list_if_needed(double dt);
  void check_fluid(const FluidAtElements& fluid) const;
  void update_voidage();
  void apply_fluid(const FluidAtElements& fluid);
  [[nodiscard]] double element_submerged_fraction(int k, const FluidAtElements& fluid) const;
  [[nodiscard]] Eigen::Vector3d drag_force(int k, const Eigen::Vector3d& relative) const;
  // Acceleration of moving element k with its added mass taken implicitly; books the added-mass
  // force into the window's fluid force.
  Eigen::Vector3d added_mass_acceleration(int k);

  DemParameters parameters_;
  std::vector<Element> elements_;
  std::vector<Material> materials_;
  std::vector<double> damping_clipped_;    // per material, no-tension normal law
  std::vector<double> damping_unclipped_;  // per material, dashpot free to pull
  std::vector<int> moving_;
  std::vector<Eigen::Vector3d> force_;
  std::vector<Eigen::Vector3d> torque_;
  // Per moving element.
  std::vector<Eigen::Vector3d> mean_fluid_force_;        // summed over sub-steps, then the mean
  std::vector<Eigen::Vector3d> mean_interaction_force_;  // drag + added mass, likewise
  std::vector<double> submerged_fraction_;
  std::vector<double> voidage_;
  std::vector<double> added_mass_normal_;            // kg, rho_f V_sub C (spheres: all directions)
  std::vector<double> added_mass_axial_;             // kg, along a log's axis
  std::vector<Eigen::Vector3d> fluid_acceleration_;  // Du/Dt of this sub-step
  // Sphere and cylinder candidate pairs, sorted by (a, b), stored by how often they are read:
  // the slot every step, the state only while the pair touches (the ContactPair the contact
  // law takes, about 180 bytes, is assembled on the stack). In the settling benchmark 40 000
  // candidates hold 10 000 contacts; streaming whole ContactPairs cost more than the law.
  std::vector<PairSlot> pair_slots_;
  std::vector<PairState> pair_states_;
  std::vector<HotPosition> hot_position_;
  std::vector<HotVelocity> hot_velocity_;
  // integrate() keeps the copies current; set_velocity and friends mark them stale.
  bool hot_valid_ = false;
  // m g per element (0 for fixed ones) for the gravity vector it was computed with: the force
  // initialisation is then a copy, without reading the elements.
  std::vector<Eigen::Vector3d> gravity_force_;
  // Two largest element sweeps (m), summed by a serial integrate(); not valid after a parallel
  // one (update_list_if_needed then finds them itself).
  double sweep_largest_ = 0.0;
  double sweep_second_ = 0.0;
  bool sweep_top_valid_ = false;
  std::vector<double> turn_angle_;  // rad, |omega| dt of this sub-step per moving element
  Eigen::Vector3d gravity_force_for_ =
      Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  std::vector<PairResult> pair_results_;     // threads > 1 only: results gathered in list order
  std::vector<ContactPair> triangle_pairs_;  // grouped by moving element
  std::vector<int> triangle_group_start_;
  double time_ = 0.0;
  double time_since_list_ = 0.0;
  double window_max_overlap_ = 0.0;
  long long step_count_ = 0;
  long long list_rebuilds_ = 0;
  bool list_valid_ = false;
  bool gate_active_ = true;
  int gate_count_ = 0;
};

inline ContactPair DemWorld::candidate_pair(int k) const {
  const PairSlot& slot = pair_slots_[k];
  const PairState& state = pair_states_[k];
  ContactPair p;
  p.a = slot.a;
  p.b = slot.b;
  p.kind = slot.kind;
  p.normal_stiffness = state.constants.normal_stiffness;
  p.tangential_stiffness = state.constants.tangential_stiffness;
  p.normal_damping = state.constants.normal_damping;
  p.tangential_damping = state.constants.tangential_damping;
  p.friction = state.constants.friction;
  p.tangential_spring = state.tangential_spring;
  p.touching = slot.touching;
  p.overlap = state.overlap;
  p.overlap_ratio = state.overlap_ratio;
  return p;
}

inline Eigen::Vector3d DemWorld::displacement(int a, int b) const {
  // Seed 004 eq. (45): the integer region difference is exact, so only the small local
  // positions are subtracted in floating point. Inline: the contact loop calls it per candidate.
  const Element& ea = elements_[a];
  const Element& eb = elements_[b];
  const Eigen::Vector3i dc = ea.cell - eb.cell;
  if (dc.isZero()) return ea.local - eb.local;
  return dc.cast<double>() * parameters_.region_size + (ea.local - eb.local);
}

}  // namespace cosim::dem
