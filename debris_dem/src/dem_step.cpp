// One DEM time step: candidate lists, contact forces and the central-difference update of seed
// 004 eq. (7)-(9), written as leapfrog (velocities at half steps, which is the backward
// difference of eq. 8 used by the dashpots and the drag). Fluid forces: dem_fluid.cpp.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "candidate_list.hpp"
#include "cosim/debris_dem/dem_world.hpp"

namespace cosim::dem {
namespace {

using Element = DemWorld::Element;

// Below this many items a parallel region costs more than it saves (and on a loaded 2-core
// machine a barrier can stall for a scheduler slice).
constexpr int kParallelThreshold = 4096;

ContactGeometry pair_geometry(const DemWorld& world, const ContactPair& p) {
  const auto& elements = world.elements();
  const Element& a = elements[p.a];
  const Element& b = elements[p.b];
  const Eigen::Vector3d d = world.displacement(p.a, p.b);
  switch (p.kind) {
    case PairKind::kSphereSphere:
      return sphere_sphere(d, a.radius, b.radius);
    case PairKind::kSphereCylinder:
      return sphere_cylinder(d, a.radius, b.axis, b.radius, b.half_length);
    case PairKind::kCylinderCylinder:
      return cylinder_cylinder(d, a.axis, a.radius, a.half_length, b.axis, b.radius, b.half_length);
    case PairKind::kSphereTriangle:
      return sphere_triangle(d, a.radius, b.edge1, b.edge2, b.normal);
    case PairKind::kCylinderTriangle:
      return cylinder_triangle(d, a.axis, a.radius, a.half_length, b.edge1, b.edge2, b.normal);
  }
  return {};
}

void release(ContactPair& p) {
  if (!p.touching) return;  // most candidates stay apart: avoid rewriting them every step
  p.touching = false;
  p.tangential_spring.setZero();
  p.force_on_a.setZero();
  p.overlap = 0.0;
  p.overlap_ratio = 0.0;
}

void evaluate(const DemWorld& world, ContactPair& p, const ContactGeometry& g, double dt,
              bool clip) {
  const auto& elements = world.elements();
  const Element& a = elements[p.a];
  const Element& b = elements[p.b];
  // Geometry is in B's anchor frame: A's center sits at the displacement, B's at the origin
  // (a triangle is fixed, so its lever does not matter).
  p.lever_a = g.point - world.displacement(p.a, p.b);
  p.lever_b = g.point;
  const Eigen::Vector3d velocity_a = a.velocity + a.angular_velocity.cross(p.lever_a);
  const Eigen::Vector3d velocity_b = b.velocity + b.angular_velocity.cross(p.lever_b);
  apply_contact_law(p, g, velocity_a - velocity_b, dt, clip);
  const double smaller_radius =
      b.kind == ElementKind::kTriangle ? a.radius : std::min(a.radius, b.radius);
  p.overlap_ratio = g.overlap / smaller_radius;
}

}  // namespace

void DemWorld::update_list_if_needed(double dt) {
  time_since_list_ += dt;
  bool rebuild = !list_valid_ || time_since_list_ >= parameters_.list_reset_interval;
  if (!rebuild && parameters_.list_sweep_guard) {
    // Seed 004 rebuilds at a fixed interval t_reset and relies on the margin; the list is also
    // rebuilt as soon as two elements could have closed the margin. Each element's sweep (path
    // of its center plus, for a log, |omega| L / 2 of its ends) is summed in integrate().
    double largest = 0.0;
    double second = 0.0;
    for (const int i : moving_) {
      const double sweep = elements_[i].sweep;
      if (sweep > largest) {
        second = largest;
        largest = sweep;
      } else if (sweep > second) {
        second = sweep;
      }
    }
    rebuild = largest + second > parameters_.list_margin;
  }
  if (!rebuild) return;
  std::vector<ContactPair> pairs;
  std::vector<ContactPair> triangle_pairs;
  std::vector<int> group_start;
  build_candidate_pairs(*this, parameters_.list_margin, pairs, triangle_pairs, group_start);
  carry_over_history(pairs_, pairs);
  carry_over_history(triangle_pairs_, triangle_pairs);
  pairs_.swap(pairs);
  triangle_pairs_.swap(triangle_pairs);
  triangle_group_start_.swap(group_start);
  for (auto& e : elements_) e.sweep = 0.0;
  time_since_list_ = 0.0;
  list_valid_ = true;
  ++list_rebuilds_;
}

void DemWorld::compute_forces(double dt) {
  const bool clip = parameters_.clip_normal_force;
  const int threads = std::max(1, parameters_.threads);
  const int n = element_count();
  for (int i = 0; i < n; ++i) {
    force_[i] = elements_[i].fixed ? Eigen::Vector3d::Zero()
                                   : Eigen::Vector3d(elements_[i].mass * parameters_.gravity);
    torque_[i].setZero();
  }
  const int pair_count = static_cast<int>(pairs_.size());
  const bool parallel_pairs = threads > 1 && pair_count > kParallelThreshold;
#pragma omp parallel for schedule(dynamic, 512) if (parallel_pairs) num_threads(threads)
  for (int k = 0; k < pair_count; ++k) {
    ContactPair& p = pairs_[k];
    const ContactGeometry g = pair_geometry(*this, p);
    if (g.touching) {
      evaluate(*this, p, g, dt, clip);
    } else {
      release(p);
    }
  }
  // Triangle contacts of one element are filtered together so that a sphere on a shared edge or
  // vertex of a mesh, or on a flat mesh near an edge, gets one contact: deepest first, then a
  // contact whose triangle point lies on or below the tangent plane of an accepted one is the
  // same surface seen from a neighbouring triangle.
  const int groups = static_cast<int>(triangle_group_start_.size()) - 1;
  const bool parallel_groups = threads > 1 && groups > kParallelThreshold / 8;
#pragma omp parallel for schedule(dynamic, 64) if (parallel_groups) num_threads(threads)
  for (int gi = 0; gi < groups; ++gi) {
    const int begin = triangle_group_start_[gi];
    const int end = triangle_group_start_[gi + 1];
    thread_local std::vector<ContactGeometry> geometry;
    thread_local std::vector<int> order;
    geometry.resize(end - begin);
    order.clear();
    for (int k = begin; k < end; ++k) {
      geometry[k - begin] = pair_geometry(*this, triangle_pairs_[k]);
      if (geometry[k - begin].touching) order.push_back(k - begin);
    }
    std::sort(order.begin(), order.end(), [&](int l, int r) {
      return geometry[l].overlap != geometry[r].overlap ? geometry[l].overlap > geometry[r].overlap
                                                        : l < r;
    });
    const bool is_sphere = triangle_pairs_[begin].kind == PairKind::kSphereTriangle;
    const double tolerance = 1e-6 * elements_[triangle_pairs_[begin].a].radius;
    thread_local std::vector<char> accepted;
    accepted.assign(end - begin, 0);
    for (std::size_t oi = 0; oi < order.size(); ++oi) {
      const ContactGeometry& gj = geometry[order[oi]];
      const Eigen::Vector3d qj = gj.point + 0.5 * gj.overlap * gj.normal;
      bool keep = true;
      for (std::size_t pi = 0; pi < oi && keep; ++pi) {
        if (!accepted[order[pi]]) continue;
        const ContactGeometry& gi_ = geometry[order[pi]];
        const Eigen::Vector3d qi = gi_.point + 0.5 * gi_.overlap * gi_.normal;
        // Positions are in each triangle's own anchor frame: shift by the anchors' offset.
        const Eigen::Vector3d shift = displacement(triangle_pairs_[begin + order[oi]].b,
                                                   triangle_pairs_[begin + order[pi]].b);
        const Eigen::Vector3d gap = qj + shift - qi;
        keep = is_sphere ? gap.dot(gi_.normal) > tolerance : gap.norm() > tolerance;
      }
      accepted[order[oi]] = keep;
    }
    for (int k = begin; k < end; ++k) {
      if (accepted[k - begin]) {
        evaluate(*this, triangle_pairs_[k], geometry[k - begin], dt, clip);
      } else {
        release(triangle_pairs_[k]);
      }
    }
  }
  // Gather in list order (deterministic sums regardless of thread count).
  double max_ratio = 0.0;
  const ContactPair* worst = nullptr;
  const auto gather = [&](const ContactPair& p) {
    if (!p.touching) return;
    force_[p.a] += p.force_on_a;
    torque_[p.a] += p.lever_a.cross(p.force_on_a);
    force_[p.b] -= p.force_on_a;
    torque_[p.b] -= p.lever_b.cross(p.force_on_a);
    if (p.overlap_ratio > max_ratio) {
      max_ratio = p.overlap_ratio;
      worst = &p;
    }
  };
  for (const auto& p : pairs_) gather(p);
  for (const auto& p : triangle_pairs_) gather(p);
  window_max_overlap_ = std::max(window_max_overlap_, max_ratio);
  if (worst != nullptr && max_ratio > parameters_.max_overlap_ratio) {
    std::ostringstream message;
    message << "DEM overlap ratio " << max_ratio << " between elements " << worst->a << " and "
            << worst->b << " exceeds max_overlap_ratio " << parameters_.max_overlap_ratio
            << " at t = " << time_ << " s (time step too large or stiffness too low)";
    throw StabilityError(message.str());
  }
}

void DemWorld::integrate(double dt, bool with_fluid) {
  const double size = parameters_.region_size;
  const int threads = std::max(1, parameters_.threads);
  const int count = static_cast<int>(moving_.size());
  const bool parallel_elements = threads > 1 && count > kParallelThreshold;
#pragma omp parallel for schedule(static) if (parallel_elements) num_threads(threads)
  for (int k = 0; k < count; ++k) {
    Element& e = elements_[moving_[k]];
    // Eq. (9) in leapfrog form: v(t + dt/2) = v(t - dt/2) + a dt, x(t + dt) = x + v dt.
    if (with_fluid && (added_mass_normal_[k] > 0.0 || added_mass_axial_[k] > 0.0)) {
      e.velocity += added_mass_acceleration(k) * dt;
    } else {
      e.velocity += force_[moving_[k]] * (e.inverse_mass * dt);
    }
    e.local += e.velocity * dt;
    // Eq. (46): move to the neighbouring region's origin when the local position leaves it.
    if (e.local.cwiseAbs().maxCoeff() > 0.75 * size) {
      const Eigen::Vector3i shift = (e.local / size).array().round().cast<int>().matrix();
      e.cell += shift;
      e.local -= shift.cast<double>() * size;
    }
    // Rotation: the world angular momentum advances with the torque, omega = R I^-1 R^T L uses
    // the full inertia of a cylinder, and the attitude quaternion turns by omega dt (unit
    // quaternions never drift into a non-rotation, unlike the attitude matrix of eq. 2).
    e.angular_momentum += torque_[moving_[k]] * dt;
    if (e.kind == ElementKind::kSphere) {
      e.angular_velocity = e.angular_momentum / e.inertia_body.x();
    } else {
      const Eigen::Matrix3d r = e.orientation.toRotationMatrix();
      e.angular_velocity = r * (r.transpose() * e.angular_momentum).cwiseQuotient(e.inertia_body);
    }
    const double angle = e.angular_velocity.norm() * dt;
    e.sweep += e.velocity.norm() * dt + e.half_length * angle;
    if (angle > 0.0) {
      const Eigen::Quaterniond turn(Eigen::AngleAxisd(angle, e.angular_velocity.normalized()));
      e.orientation = (turn * e.orientation).normalized();
      e.axis = e.orientation * Eigen::Vector3d::UnitZ();
    }
  }
}

void DemWorld::check_stability() const {
  for (const int i : moving_) {
    const Element& e = elements_[i];
    const char* quantity = nullptr;
    if (!e.local.allFinite()) {
      quantity = "position";
    } else if (!e.velocity.allFinite()) {
      quantity = "velocity";
    } else if (!e.angular_momentum.allFinite()) {
      quantity = "angular momentum";
    }
    if (quantity != nullptr) {
      std::ostringstream message;
      message << "DEM element " << i << ": " << quantity << " is not finite at t = " << time_
              << " s";
      throw StabilityError(message.str());
    }
    const Eigen::Vector3d p = position(i);
    if ((p.array() < parameters_.domain_min.array()).any() ||
        (p.array() > parameters_.domain_max.array()).any()) {
      std::ostringstream message;
      message << "DEM element " << i << ": position (" << p.transpose()
              << ") left the domain bounding box at t = " << time_ << " s";
      throw StabilityError(message.str());
    }
  }
}

void DemWorld::step(double dt) {
  update_list_if_needed(dt);
  compute_forces(dt);
  integrate(dt, false);
  time_ += dt;
  ++step_count_;
  check_stability();
}

}  // namespace cosim::dem
