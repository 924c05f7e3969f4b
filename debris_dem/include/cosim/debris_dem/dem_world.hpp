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
#include "cosim/debris_dem/dem_parameters.hpp"

namespace cosim::dem {

// Thrown on NaN, excessive overlap or escape from the domain; the message names the element
// and the quantity so the coupler can report it with the window.
class StabilityError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
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
  // Body -> world. A sphere keeps the attitude it was built with (the identity): nothing of a
  // sphere (contacts, fluid forces, output) depends on it, so it is not integrated, as in
  // LIGGGHTS' nve/sphere; its angular velocity is.
  [[nodiscard]] Eigen::Quaterniond orientation(int element) const;
  [[nodiscard]] Eigen::Vector3d axis(int element) const;  // cylinder axis (world)
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
  // Line-aligned, with all that a sphere's integration reads and writes in the first three
  // cache lines (the contact loops read the compact copies below instead).
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
    double sweep = 0.0;  // bound on surface-point travel since the last list build
    Eigen::Vector3d angular_momentum = Eigen::Vector3d::Zero();  // world frame
    Eigen::Vector3d inertia_body = Eigen::Vector3d::Zero();      // principal, body z = axis
    Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
    Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  // cylinder axis, world frame
    double half_length = 0.0;
    double mass = 0.0;
    double bounding_radius = 0.0;
    int material = 0;
    // Triangle geometry relative to vertex a (the anchor).
    Eigen::Vector3d edge1 = Eigen::Vector3d::Zero();
    Eigen::Vector3d edge2 = Eigen::Vector3d::Zero();
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  };
  // 12 bytes: the candidate loop streams every slot each step (a sphere pair's reach is the sum
  // of the radii in the hot copies it reads anyway).
  struct PairSlot {
    int a = -1;
    int b = -1;
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
  // Reads and writes the evolving state (checkpoint.cpp); materials come from the scene.
  friend struct DemWorldCheckpoint;

  // Largest overlap ratio of a step and its pair, taken in gather order (the first pair wins a
  // tie).
  struct WorstOverlap {
    double ratio = 0.0;
    int a = -1;
    int b = -1;
  };
  // Per-thread scratch of the triangle filter (one moving element's triangle candidates).
  struct TriangleScratch {
    std::vector<ContactGeometry> geometry;
    std::vector<int> order;
    std::vector<char> accepted;
  };

  int add_element(Element element, const Eigen::Vector3d& anchor, const Material& material);
  int material_index(const Material& material);
  void compute_forces(double dt);
  // Force and torque start from gravity; the compact copies are refreshed if stale.
  void reset_forces();
  // displacement(a, b) on the compact copies (same operations, same result).
  [[nodiscard]] Eigen::Vector3d hot_displacement(int a, int b) const;
  // Adds a pair's force to both elements (A gets force_on_a, B minus it) and notes its ratio.
  void gather(int a, int b, const PairResult& r, double overlap_ratio, WorstOverlap& worst);
  // Candidate k (sphere or cylinder pair) with d = hot_displacement(a, b): geometry and contact
  // law on its slot and state; false (spring released) when apart.
  bool pair_contact(int k, const Eigen::Vector3d& d, double dt, bool clip, PairResult& r);
  void pair_contacts(double dt, bool clip, WorstOverlap& worst);
  void triangle_contacts(double dt, bool clip, WorstOverlap& worst);
  void triangle_group_contacts(int group, double dt, bool clip, TriangleScratch& scratch);
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
