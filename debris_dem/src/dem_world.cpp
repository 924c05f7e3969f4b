// DemWorld construction, accessors and energies. The time step lives in dem_step.cpp.
#include "cosim/debris_dem/dem_world.hpp"

#include <cmath>
#include <numbers>

namespace cosim::dem {

double Material::effective_damping_ratio(bool clipped) const {
  if (restitution >= 1.0) return 0.0;
  if (restitution > 0.0) return damping_ratio_for_restitution(restitution, clipped);
  return damping_ratio;
}

void validate_parameters(const DemParameters& p) {
  scenario::check_parameters(p, "DemParameters");
}

void validate_material(const Material& m) {
  scenario::check_parameters(m, "Material");
  try {
    (void)m.effective_damping_ratio(true);
    (void)m.effective_damping_ratio(false);
  } catch (const std::invalid_argument&) {
    throw scenario::ParameterError(
        "Material", "restitution",
        "value " + scenario::format_number(m.restitution) +
            " is below what any damping ratio gives (about 1e-16): use 0 and set damping_ratio");
  }
}

DemWorld::DemWorld(DemParameters parameters) : parameters_(std::move(parameters)) {
  validate_parameters(parameters_);
}
DemWorld::~DemWorld() = default;
DemWorld::DemWorld(DemWorld&&) noexcept = default;
DemWorld& DemWorld::operator=(DemWorld&&) noexcept = default;

int DemWorld::material_index(const Material& m) {
  for (int i = 0; i < static_cast<int>(materials_.size()); ++i) {
    const Material& o = materials_[i];
    if (o.density == m.density && o.normal_stiffness == m.normal_stiffness &&
        o.tangential_stiffness == m.tangential_stiffness && o.damping_ratio == m.damping_ratio &&
        o.restitution == m.restitution && o.friction == m.friction) {
      return i;
    }
  }
  validate_material(m);
  materials_.push_back(m);
  damping_clipped_.push_back(m.effective_damping_ratio(true));
  damping_unclipped_.push_back(m.effective_damping_ratio(false));
  return static_cast<int>(materials_.size()) - 1;
}

double DemWorld::damping_ratio(int material) const {
  return parameters_.clip_normal_force ? damping_clipped_.at(material)
                                       : damping_unclipped_.at(material);
}

int DemWorld::add_element(Element element, const Eigen::Vector3d& anchor,
                          const Material& material) {
  if (!anchor.allFinite()) throw std::invalid_argument("DemWorld: element position not finite");
  element.material = material_index(material);
  // Seed 004 eq. (45): position = region origin B^m + local position L^m.
  const double size = parameters_.region_size;
  const Eigen::Vector3d scaled = anchor / size;
  element.cell = scaled.array().round().cast<int>().matrix();
  element.local = anchor - element.cell.cast<double>() * size;
  if (element.fixed) {
    element.inverse_mass = 0.0;
  } else {
    element.inverse_mass = 1.0 / element.mass;
    moving_.push_back(static_cast<int>(elements_.size()));
    mean_fluid_force_.emplace_back(Eigen::Vector3d::Zero());
    mean_interaction_force_.emplace_back(Eigen::Vector3d::Zero());
    submerged_fraction_.push_back(0.0);
    voidage_.push_back(1.0);
    added_mass_normal_.push_back(0.0);
    added_mass_axial_.push_back(0.0);
    fluid_acceleration_.emplace_back(Eigen::Vector3d::Zero());
  }
  elements_.push_back(element);
  force_.emplace_back(Eigen::Vector3d::Zero());
  torque_.emplace_back(Eigen::Vector3d::Zero());
  list_valid_ = false;
  hot_valid_ = false;
  gravity_force_.clear();
  return static_cast<int>(elements_.size()) - 1;
}

int DemWorld::add_sphere(const Eigen::Vector3d& center, double radius, const Material& material,
                         bool fixed) {
  if (!(radius > 0.0)) throw std::invalid_argument("add_sphere: radius must be positive");
  Element e;
  e.kind = ElementKind::kSphere;
  e.fixed = fixed;
  e.radius = radius;
  e.mass = material.density * 4.0 / 3.0 * std::numbers::pi * radius * radius * radius;
  e.inertia_body.setConstant(0.4 * e.mass * radius * radius);
  e.bounding_radius = radius;
  return add_element(e, center, material);
}

int DemWorld::add_cylinder(const Eigen::Vector3d& center, const Eigen::Vector3d& axis_unit,
                           double radius, double length, const Material& material, bool fixed) {
  if (!(radius > 0.0) || !(length > 0.0) || !(axis_unit.norm() > 0.0)) {
    throw std::invalid_argument("add_cylinder: radius, length and axis must be non-zero");
  }
  Element e;
  e.kind = ElementKind::kCylinder;
  e.fixed = fixed;
  e.radius = radius;
  e.half_length = 0.5 * length;
  e.axis = axis_unit.normalized();
  e.orientation = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), e.axis);
  e.mass = material.density * std::numbers::pi * radius * radius * length;
  // Solid cylinder about its center: axial m r^2 / 2, transverse m (3 r^2 + L^2) / 12.
  const double transverse = e.mass * (3.0 * radius * radius + length * length) / 12.0;
  e.inertia_body = Eigen::Vector3d(transverse, transverse, 0.5 * e.mass * radius * radius);
  e.bounding_radius = std::hypot(radius, e.half_length);
  return add_element(e, center, material);
}

int DemWorld::add_triangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                           const Eigen::Vector3d& c, const Material& material) {
  Element e;
  e.kind = ElementKind::kTriangle;
  e.fixed = true;
  e.edge1 = b - a;
  e.edge2 = c - a;
  const Eigen::Vector3d normal = e.edge1.cross(e.edge2);
  if (!(normal.norm() > 0.0)) throw std::invalid_argument("add_triangle: degenerate triangle");
  e.normal = normal.normalized();
  const Eigen::Vector3d centroid = (e.edge1 + e.edge2) / 3.0;
  e.bounding_radius =
      std::max({centroid.norm(), (e.edge1 - centroid).norm(), (e.edge2 - centroid).norm()});
  return add_element(e, a, material);
}

int DemWorld::add_gate(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                       const Eigen::Vector3d& p2, const Eigen::Vector3d& p3,
                       const Material& material) {
  const int gate = gate_count_++;
  const int t0 = add_triangle(p0, p1, p2, material);
  const int t1 = add_triangle(p0, p2, p3, material);
  elements_[t0].gate = gate;
  elements_[t1].gate = gate;
  elements_[t0].enabled = gate_active_;
  elements_[t1].enabled = gate_active_;
  return gate;
}

void DemWorld::set_gate_active(bool active) {
  gate_active_ = active;
  for (auto& e : elements_) {
    if (e.gate >= 0) e.enabled = active;
  }
  list_valid_ = false;
}

int DemWorld::element_count() const {
  return static_cast<int>(elements_.size());
}
ElementKind DemWorld::kind(int i) const {
  return elements_.at(i).kind;
}
bool DemWorld::is_fixed(int i) const {
  return elements_.at(i).fixed;
}
Eigen::Vector3d DemWorld::position(int i) const {
  const Element& e = elements_.at(i);
  return e.cell.cast<double>() * parameters_.region_size + e.local;
}
Eigen::Vector3d DemWorld::velocity(int i) const {
  return elements_.at(i).velocity;
}
Eigen::Vector3d DemWorld::angular_velocity(int i) const {
  return elements_.at(i).angular_velocity;
}
Eigen::Quaterniond DemWorld::orientation(int i) const {
  return elements_.at(i).orientation;
}
Eigen::Vector3d DemWorld::axis(int i) const {
  return elements_.at(i).axis;
}
double DemWorld::radius(int i) const {
  return elements_.at(i).radius;
}
double DemWorld::length(int i) const {
  return 2.0 * elements_.at(i).half_length;
}
double DemWorld::mass(int i) const {
  return elements_.at(i).mass;
}
double DemWorld::volume(int i) const {
  const Element& e = elements_.at(i);
  if (e.kind == ElementKind::kTriangle) return 0.0;
  return e.mass / materials_[e.material].density;
}
std::vector<Eigen::Vector3d> DemWorld::triangle_vertices(int i) const {
  const Element& e = elements_.at(i);
  const Eigen::Vector3d a = position(i);
  return {a, a + e.edge1, a + e.edge2};
}

void DemWorld::set_velocity(int i, const Eigen::Vector3d& v) {
  if (elements_.at(i).fixed) throw std::invalid_argument("set_velocity: element is fixed");
  elements_[i].velocity = v;
  hot_valid_ = false;
}

void DemWorld::set_angular_velocity(int i, const Eigen::Vector3d& omega) {
  Element& e = elements_.at(i);
  if (e.fixed) throw std::invalid_argument("set_angular_velocity: element is fixed");
  const Eigen::Matrix3d r = e.orientation.toRotationMatrix();
  e.angular_momentum = r * e.inertia_body.asDiagonal() * r.transpose() * omega;
  e.angular_velocity = omega;
  hot_valid_ = false;
}

std::vector<Eigen::Vector3d> DemWorld::element_centers() const {
  std::vector<Eigen::Vector3d> out;
  out.reserve(moving_.size());
  for (const int i : moving_) out.push_back(position(i));
  return out;
}

std::vector<Eigen::Vector3d> DemWorld::element_velocities() const {
  std::vector<Eigen::Vector3d> out;
  out.reserve(moving_.size());
  for (const int i : moving_) out.push_back(elements_[i].velocity);
  return out;
}

double DemWorld::stable_dt() const {
  // Seed 004 section 4.1(3) picks K so that T/dt ~ 50 with T = 2 pi sqrt(m/k); here
  // dt = safety_factor sqrt(m/k) with m the smallest translational or rotational (I / rho^2,
  // rho the farthest surface point) mass and k the stiffest spring.
  double critical_mass = std::numeric_limits<double>::infinity();
  for (const int i : moving_) {
    const Element& e = elements_[i];
    // Rotational mass seen at the contact: about the axis the lever is the radius, about a
    // transverse axis it is the distance to the farthest rim point.
    const double axial = e.inertia_body.z() / (e.radius * e.radius);
    const double transverse = e.inertia_body.x() / (e.bounding_radius * e.bounding_radius);
    critical_mass = std::min({critical_mass, e.mass, axial, transverse});
  }
  double stiffness = 0.0;
  for (const Material& m : materials_) {
    stiffness = std::max({stiffness, m.normal_stiffness, m.tangential_stiffness});
  }
  if (!std::isfinite(critical_mass) || stiffness <= 0.0) {
    // Nothing to resolve: the seed's list interval (1e-3 s) when no finite one is set.
    const double interval = parameters_.list_reset_interval;
    return std::isfinite(interval) ? interval : 1.0e-3;
  }
  return parameters_.safety_factor * std::sqrt(critical_mass / stiffness);
}

double DemWorld::kinetic_energy() const {
  double energy = 0.0;
  for (const int i : moving_) {
    const Element& e = elements_[i];
    energy +=
        0.5 * e.mass * e.velocity.squaredNorm() + 0.5 * e.angular_velocity.dot(e.angular_momentum);
  }
  return energy;
}

double DemWorld::potential_energy() const {
  double energy = 0.0;
  for (const int i : moving_) energy -= elements_[i].mass * parameters_.gravity.dot(position(i));
  return energy;
}

double DemWorld::elastic_energy() const {
  double energy = 0.0;
  for (int k = 0; k < static_cast<int>(pair_slots_.size()); ++k) {
    if (pair_slots_[k].touching) energy += contact_elastic_energy(candidate_pair(k));
  }
  for (const auto& p : triangle_pairs_) energy += contact_elastic_energy(p);
  return energy;
}

int DemWorld::contact_count() const {
  int count = 0;
  for (const auto& slot : pair_slots_) count += slot.touching ? 1 : 0;
  for (const auto& p : triangle_pairs_) count += p.touching ? 1 : 0;
  return count;
}

}  // namespace cosim::dem
