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
  // restitution > 0 it overrides: zeta = -ln e / sqrt(pi^2 + ln^2 e) (references/dem_contact.md).
  double damping_ratio = 0.2;
  double restitution = 0.0;
  double friction = 0.404;  // tan(phi) of the Mohr-Coulomb limit, cohesion c = 0 (table 3)

  [[nodiscard]] double effective_damping_ratio() const;
};

struct DemParameters {
  // Gravity in the world frame; slope_gravity() in scenes.hpp tilts it for a flume frame.
  Eigen::Vector3d gravity{0.0, 0.0, -9.81};
  double fluid_density = 1000.0;
  double drag_coefficient_sphere = 0.49;  // seed 004 section 4.1(3), from Hashimoto et al.
  // Seed 004 gives a log the drag of a sphere of equal projected area; here the area normal to
  // the relative flow, 2 r L sin + pi r^2 cos, is used with this coefficient.
  double drag_coefficient_cylinder = 0.49;
  double list_margin = 5.0e-3;          // r_dam of table 3: extra reach of candidate lists
  double list_reset_interval = 1.0e-3;  // t_reset of table 3 (s)
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
  // Sub-cycles window_dt. Inputs are per moving element (empty vectors: no fluid).
  WindowReport advance(double window_dt, const std::vector<Eigen::Vector3d>& ambient_velocity,
                       const std::vector<double>& water_fraction);
  // One sub-step of dt without fluid (tests, packing).
  void step(double dt);
  [[nodiscard]] const std::vector<Eigen::Vector3d>& window_mean_fluid_force() const {
    return mean_fluid_force_;
  }

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
  struct Element {
    ElementKind kind = ElementKind::kSphere;
    bool fixed = false;
    bool enabled = true;  // false for a removed gate
    int gate = -1;        // gate id of a gate triangle
    Eigen::Vector3i cell =
        Eigen::Vector3i::Zero();  // local origin B^m = cell * region_size (seed 004 eq. 45)
    Eigen::Vector3d local = Eigen::Vector3d::Zero();
    Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
    Eigen::Vector3d angular_momentum = Eigen::Vector3d::Zero();  // world frame
    Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();  // world frame
    Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
    Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  // cylinder axis, world frame
    double radius = 0.0;
    double half_length = 0.0;
    double mass = 0.0;
    double inverse_mass = 0.0;
    Eigen::Vector3d inertia_body = Eigen::Vector3d::Zero();  // principal, body z = axis
    double bounding_radius = 0.0;
    double sweep = 0.0;  // bound on surface-point travel since the last list build
    int material = 0;
    // Triangle geometry relative to vertex a (the anchor).
    Eigen::Vector3d edge1 = Eigen::Vector3d::Zero();
    Eigen::Vector3d edge2 = Eigen::Vector3d::Zero();
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  };
  [[nodiscard]] const std::vector<Element>& elements() const { return elements_; }
  [[nodiscard]] const std::vector<Material>& materials() const { return materials_; }
  // Displacement from element b's anchor to element a's anchor via local origins (eq. 45-46).
  [[nodiscard]] Eigen::Vector3d displacement(int a, int b) const;

 private:
  int add_element(Element element, const Eigen::Vector3d& anchor, const Material& material);
  int material_index(const Material& material);
  void compute_forces(double dt);
  void integrate(double dt);
  void check_stability() const;
  void update_list_if_needed(double dt);
  void apply_fluid(const std::vector<Eigen::Vector3d>& ambient_velocity,
                   const std::vector<double>& water_fraction, bool accumulate);

  DemParameters parameters_;
  std::vector<Element> elements_;
  std::vector<Material> materials_;
  std::vector<int> moving_;
  std::vector<Eigen::Vector3d> force_;
  std::vector<Eigen::Vector3d> torque_;
  std::vector<Eigen::Vector3d> fluid_force_;  // per moving element, current sub-step
  std::vector<Eigen::Vector3d> mean_fluid_force_;
  std::vector<ContactPair> pairs_;
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

}  // namespace cosim::dem
