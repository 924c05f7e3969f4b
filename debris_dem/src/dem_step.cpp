// One DEM time step: candidate lists, contact forces and the central-difference update of seed
// 004 eq. (7)-(9), written as leapfrog (velocities at half steps, which is the backward
// difference of eq. 8 used by the dashpots and the drag). Fluid forces: dem_fluid.cpp.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "attitude.hpp"
#include "candidate_list.hpp"
#include "cosim/debris_dem/dem_world.hpp"

namespace cosim::dem {
namespace {

using Element = DemWorld::Element;

// Below this many items a parallel region costs more than it saves (and on a loaded 2-core
// machine a barrier can stall for a scheduler slice).
constexpr int kParallelThreshold = 4096;

// The contact law of a pair from the compact velocity copies (evaluate() without the Element
// reads): levers from each anchor to the contact point, relative velocity at that point.
// d: displacement from B's anchor to A's.
template <class HotVelocity>
void apply_law_at_contact_point(ContactPair& p, const ContactGeometry& g, const Eigen::Vector3d& d,
                                const HotVelocity& va, const HotVelocity& vb, double dt,
                                bool clip) {
  p.lever_a = g.point - d;
  p.lever_b = g.point;
  const Eigen::Vector3d velocity_a = va.velocity + va.angular_velocity.cross(p.lever_a);
  const Eigen::Vector3d velocity_b = vb.velocity + vb.angular_velocity.cross(p.lever_b);
  apply_contact_law(p, g, velocity_a - velocity_b, dt, clip);
}

// d: displacement from B's anchor to A's (DemWorld::displacement(a, b)).
ContactGeometry pair_geometry(const DemWorld& world, int ia, int ib, PairKind kind,
                              const Eigen::Vector3d& d) {
  const auto& elements = world.elements();
  const Element& a = elements[ia];
  const Element& b = elements[ib];
  switch (kind) {
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

void release(DemWorld::PairState& s) {
  s.tangential_spring.setZero();
  s.overlap = 0.0;
  s.overlap_ratio = 0.0;
}

// A candidate found apart: its spring is released once, when it separates.
void separate(DemWorld::PairSlot& slot, DemWorld::PairState& state) {
  if (!slot.touching) return;
  release(state);
  slot.touching = false;
}

// displacement(a, b) on the compact copies of a and b (same operations, same result). Forced
// inline: it is the body of the candidate loop, which GCC 12 otherwise calls it from.
[[gnu::always_inline]] inline Eigen::Vector3d displacement_between(const DemWorld::HotPosition& pa,
                                                                   const DemWorld::HotPosition& pb,
                                                                   double region_size) {
  const Eigen::Vector3i dc = pa.cell - pb.cell;
  if (dc.isZero()) return pa.local - pb.local;
  return dc.cast<double>() * region_size + (pa.local - pb.local);
}

bool pair_order(const DemWorld::PairSlot& l, const ContactPair& r) {
  return l.a != r.a ? l.a < r.a : l.b < r.b;
}

}  // namespace

void DemWorld::update_list_if_needed(double dt) {
  time_since_list_ += dt;
  bool rebuild = !list_valid_ || time_since_list_ >= parameters_.list_reset_interval;
  if (!rebuild && parameters_.list_sweep_guard) {
    // Seed 004 rebuilds at a fixed interval t_reset and relies on the margin; the list is also
    // rebuilt as soon as two elements could have closed the margin. Each element's sweep (path
    // of its center plus, for a log, |omega| L / 2 of its ends) is summed in integrate().
    double largest = sweep_largest_;
    double second = sweep_second_;
    if (!sweep_top_valid_) {
      largest = 0.0;
      second = 0.0;
      for (const int i : moving_) {
        const double sweep = elements_[i].sweep;
        if (sweep > largest) {
          second = largest;
          largest = sweep;
        } else if (sweep > second) {
          second = sweep;
        }
      }
    }
    rebuild = largest + second > parameters_.list_margin;
  }
  if (!rebuild) return;
  std::vector<ContactPair> pairs;
  std::vector<ContactPair> triangle_pairs;
  std::vector<int> group_start;
  build_candidate_pairs(*this, parameters_.list_margin, pairs, triangle_pairs, group_start);
  // Split the new list into slots and states, carrying the spring history of pairs in both
  // lists (both sorted by a, b). A touching pair is always in the new list: it lies within the
  // margin.
  std::vector<PairSlot> slots(pairs.size());
  std::vector<PairState> states(pairs.size());
  std::size_t old = 0;
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    const ContactPair& p = pairs[k];
    PairSlot& slot = slots[k];
    PairState& state = states[k];
    slot.a = p.a;
    slot.b = p.b;
    slot.kind = p.kind;
    state.constants = {p.normal_stiffness, p.tangential_stiffness, p.normal_damping,
                       p.tangential_damping, p.friction};
    while (old < pair_slots_.size() && pair_order(pair_slots_[old], p)) ++old;
    if (old < pair_slots_.size() && pair_slots_[old].a == p.a && pair_slots_[old].b == p.b) {
      slot.touching = pair_slots_[old].touching;
      state.tangential_spring = pair_states_[old].tangential_spring;
      state.overlap = pair_states_[old].overlap;
      state.overlap_ratio = pair_states_[old].overlap_ratio;
    }
  }
  pair_slots_.swap(slots);
  pair_states_.swap(states);
  carry_over_history(triangle_pairs_, triangle_pairs);
  triangle_pairs_.swap(triangle_pairs);
  triangle_group_start_.swap(group_start);
  for (auto& e : elements_) e.sweep = 0.0;
  sweep_largest_ = 0.0;
  sweep_second_ = 0.0;
  sweep_top_valid_ = true;
  time_since_list_ = 0.0;
  list_valid_ = true;
  ++list_rebuilds_;
}

void DemWorld::reset_forces() {
  const int n = element_count();
  if (static_cast<int>(gravity_force_.size()) != n || gravity_force_for_ != parameters_.gravity) {
    gravity_force_.resize(n);
    for (int i = 0; i < n; ++i) {
      const Element& e = elements_[i];
      gravity_force_[i] =
          e.fixed ? Eigen::Vector3d::Zero() : Eigen::Vector3d(e.mass * parameters_.gravity);
    }
    gravity_force_for_ = parameters_.gravity;
  }
  std::copy(gravity_force_.begin(), gravity_force_.end(), force_.begin());
  std::fill(torque_.begin(), torque_.end(), Eigen::Vector3d::Zero());
  if (!hot_valid_ || static_cast<int>(hot_position_.size()) != n) {
    hot_position_.resize(n);
    hot_velocity_.resize(n);
    for (int i = 0; i < n; ++i) {
      const Element& e = elements_[i];
      hot_position_[i] = {e.local, e.radius, e.cell, 0};
      hot_velocity_[i] = {e.velocity, e.angular_velocity};
    }
    hot_valid_ = true;
  }
}

inline Eigen::Vector3d DemWorld::hot_displacement(int a, int b) const {
  return displacement_between(hot_position_[a], hot_position_[b], parameters_.region_size);
}

inline void DemWorld::gather(int a, int b, const PairResult& r, double overlap_ratio,
                             WorstOverlap& worst) {
  force_[a] += r.force_on_a;
  torque_[a] += r.lever_a.cross(r.force_on_a);
  force_[b] -= r.force_on_a;
  torque_[b] -= r.lever_b.cross(r.force_on_a);
  if (overlap_ratio > worst.ratio) worst = {overlap_ratio, a, b};
}

// evaluate() on the compact copies, without a ContactPair: the levers run from each anchor to
// the contact point, the law takes the relative velocity there and keeps the spring in the
// state. B is a sphere or cylinder here, never a triangle.
inline bool DemWorld::pair_contact(int k, const Eigen::Vector3d& d, double dt, bool clip,
                                   PairResult& r) {
  PairSlot& slot = pair_slots_[k];
  PairState& state = pair_states_[k];
  const HotPosition& pa = hot_position_[slot.a];
  const HotPosition& pb = hot_position_[slot.b];
  const ContactGeometry g = slot.kind == PairKind::kSphereSphere
                                ? sphere_sphere(d, pa.radius, pb.radius)
                                : pair_geometry(*this, slot.a, slot.b, slot.kind, d);
  if (!g.touching) {
    separate(slot, state);
    return false;
  }
  r.lever_a = g.point - d;
  r.lever_b = g.point;
  const HotVelocity& va = hot_velocity_[slot.a];
  const HotVelocity& vb = hot_velocity_[slot.b];
  const Eigen::Vector3d velocity_a = va.velocity + va.angular_velocity.cross(r.lever_a);
  const Eigen::Vector3d velocity_b = vb.velocity + vb.angular_velocity.cross(r.lever_b);
  r.force_on_a = contact_force(state.constants, g.overlap, g.normal, velocity_a - velocity_b, dt,
                               clip, state.tangential_spring);
  state.overlap = g.overlap;
  state.overlap_ratio = g.overlap / std::min(pa.radius, pb.radius);
  slot.touching = true;
  return true;
}

void DemWorld::pair_contacts(double dt, bool clip, WorstOverlap& worst) {
  const int threads = std::max(1, parameters_.threads);
  const int pair_count = static_cast<int>(pair_slots_.size());
  // The array starts and the region size as locals: the loop stores bool flags, which may alias
  // any member, and read through this every candidate would reload them.
  PairSlot* const slots = pair_slots_.data();
  PairState* const states = pair_states_.data();
  const HotPosition* const hot = hot_position_.data();
  const double region_size = parameters_.region_size;
  // A sphere pair farther apart than its radii is rejected with the comparison sphere_sphere()
  // makes, reading only its slot and positions (three in four candidates of a settled pile); its
  // flag is written only when it has just separated.
  const auto apart = [&](const PairSlot& slot, const Eigen::Vector3d& d) {
    if (slot.kind != PairKind::kSphereSphere) return false;
    const double reach = hot[slot.a].radius + hot[slot.b].radius;
    return d.squaredNorm() > reach * reach;
  };
  if (threads > 1 && pair_count > kParallelThreshold) {
    pair_results_.resize(pair_slots_.size());
#pragma omp parallel for schedule(dynamic, 512) num_threads(threads)
    for (int k = 0; k < pair_count; ++k) {
      const Eigen::Vector3d d = displacement_between(hot[slots[k].a], hot[slots[k].b], region_size);
      if (apart(slots[k], d)) {
        separate(slots[k], states[k]);
      } else {
        pair_contact(k, d, dt, clip, pair_results_[k]);
      }
    }
    for (int k = 0; k < pair_count; ++k) {
      const PairSlot& slot = slots[k];
      if (slot.touching) gather(slot.a, slot.b, pair_results_[k], states[k].overlap_ratio, worst);
    }
    return;
  }
  // One pass: the triangle contacts read only velocities, never force_, so gathering here adds
  // to each element in the same order as gathering after them.
  PairResult r;
  for (int k = 0; k < pair_count; ++k) {
    const PairSlot& slot = slots[k];
    const Eigen::Vector3d d = displacement_between(hot[slot.a], hot[slot.b], region_size);
    if (apart(slot, d)) {
      separate(slots[k], states[k]);
    } else if (pair_contact(k, d, dt, clip, r)) {
      gather(slot.a, slot.b, r, states[k].overlap_ratio, worst);
    }
  }
}

// Triangle contacts of one element are filtered together so that a sphere on a shared edge or
// vertex of a mesh, or on a flat mesh near an edge, gets one contact: deepest first, then a
// contact whose triangle point lies on or below the tangent plane of an accepted one is the same
// surface seen from a neighbouring triangle.
void DemWorld::triangle_group_contacts(int group, double dt, bool clip, TriangleScratch& scratch) {
  const int begin = triangle_group_start_[group];
  const int end = triangle_group_start_[group + 1];
  std::vector<ContactGeometry>& geometry = scratch.geometry;
  std::vector<int>& order = scratch.order;
  geometry.resize(end - begin);
  order.clear();
  for (int k = begin; k < end; ++k) {
    const ContactPair& p = triangle_pairs_[k];
    ContactGeometry& g = geometry[k - begin];
    // The moving element through the compact copy (its Element is a cache miss: these are the
    // elements next to a wall, spread over the array); triangles are few and stay cached.
    const Eigen::Vector3d d = hot_displacement(p.a, p.b);
    if (p.kind == PairKind::kSphereTriangle) {
      const Element& tri = elements_[p.b];
      const double radius = hot_position_[p.a].radius;
      // A sphere farther from the triangle's plane than its radius cannot touch it (the closest
      // point of the triangle is no nearer than the plane); the slack of 1e-9 radius is far
      // above the round-off of both distances (1e-16 m here), so exactly the pairs
      // sphere_triangle() finds apart are skipped.
      if (std::abs(d.dot(tri.normal)) > radius * (1.0 + 1e-9)) {
        g = ContactGeometry{};
        continue;
      }
      g = sphere_triangle(d, radius, tri.edge1, tri.edge2, tri.normal);
    } else {
      g = pair_geometry(*this, p.a, p.b, p.kind, d);
    }
    if (g.touching) order.push_back(k - begin);
  }
  std::sort(order.begin(), order.end(), [&](int l, int r) {
    return geometry[l].overlap != geometry[r].overlap ? geometry[l].overlap > geometry[r].overlap
                                                      : l < r;
  });
  const bool is_sphere = triangle_pairs_[begin].kind == PairKind::kSphereTriangle;
  const double tolerance = 1e-6 * elements_[triangle_pairs_[begin].a].radius;
  std::vector<char>& accepted = scratch.accepted;
  accepted.assign(end - begin, 0);
  for (std::size_t oi = 0; oi < order.size(); ++oi) {
    const ContactGeometry& gj = geometry[order[oi]];
    const Eigen::Vector3d qj = gj.point + 0.5 * gj.overlap * gj.normal;
    bool keep = true;
    for (std::size_t pi = 0; pi < oi && keep; ++pi) {
      if (!accepted[order[pi]]) continue;
      const ContactGeometry& gi = geometry[order[pi]];
      const Eigen::Vector3d qi = gi.point + 0.5 * gi.overlap * gi.normal;
      // Positions are in each triangle's own anchor frame: shift by the anchors' offset.
      const Eigen::Vector3d shift =
          displacement(triangle_pairs_[begin + order[oi]].b, triangle_pairs_[begin + order[pi]].b);
      const Eigen::Vector3d gap = qj + shift - qi;
      keep = is_sphere ? gap.dot(gi.normal) > tolerance : gap.norm() > tolerance;
    }
    accepted[order[oi]] = keep;
  }
  for (int k = begin; k < end; ++k) {
    ContactPair& p = triangle_pairs_[k];
    if (!accepted[k - begin]) {
      release(p);
      continue;
    }
    // evaluate() on the compact copies; B is a fixed triangle (its lever does not matter, its
    // velocities are zero in the copy as in the Element).
    const ContactGeometry& g = geometry[k - begin];
    const Eigen::Vector3d d = hot_displacement(p.a, p.b);
    apply_law_at_contact_point(p, g, d, hot_velocity_[p.a], hot_velocity_[p.b], dt, clip);
    p.overlap_ratio = g.overlap / hot_position_[p.a].radius;
  }
}

void DemWorld::triangle_contacts(double dt, bool clip, WorstOverlap& worst) {
  const int threads = std::max(1, parameters_.threads);
  const int groups = static_cast<int>(triangle_group_start_.size()) - 1;
  const bool parallel_groups = threads > 1 && groups > kParallelThreshold / 8;
  if (parallel_groups) {
#pragma omp parallel num_threads(threads)
    {
      TriangleScratch scratch;
#pragma omp for schedule(dynamic, 64)
      for (int gi = 0; gi < groups; ++gi) triangle_group_contacts(gi, dt, clip, scratch);
    }
  } else {
    thread_local TriangleScratch scratch;  // kept between steps: no allocation per step
    for (int gi = 0; gi < groups; ++gi) triangle_group_contacts(gi, dt, clip, scratch);
  }
  for (const auto& p : triangle_pairs_) {
    if (p.touching) gather(p.a, p.b, {p.force_on_a, p.lever_a, p.lever_b}, p.overlap_ratio, worst);
  }
}

void DemWorld::compute_forces(double dt) {
  const bool clip = parameters_.clip_normal_force;
  reset_forces();
  WorstOverlap worst;
  pair_contacts(dt, clip, worst);
  triangle_contacts(dt, clip, worst);
  window_max_overlap_ = std::max(window_max_overlap_, worst.ratio);
  if (worst.a >= 0 && worst.ratio > parameters_.max_overlap_ratio) {
    std::ostringstream message;
    message << "DEM overlap ratio " << worst.ratio << " between elements " << worst.a << " and "
            << worst.b << " exceeds max_overlap_ratio " << parameters_.max_overlap_ratio
            << " at t = " << time_ << " s (time step too large or stiffness too low)";
    throw StabilityError(message.str());
  }
}

bool DemWorld::integrate(double dt, bool with_fluid) {
  const double size = parameters_.region_size;
  const int threads = std::max(1, parameters_.threads);
  const int count = static_cast<int>(moving_.size());
  const bool parallel_elements = threads > 1 && count > kParallelThreshold;
  // Copies are only kept current once compute_forces() made them so (the next call refreshes
  // them otherwise).
  const bool keep_hot = hot_valid_ && hot_position_.size() == elements_.size();
  const Eigen::Vector3d& domain_min = parameters_.domain_min;
  const Eigen::Vector3d& domain_max = parameters_.domain_max;
  bool suspect = false;
  double largest = 0.0;  // m, largest sweep of a moving element since the last list build
  double second = 0.0;   // m, second largest
  // clang-format off
#pragma omp parallel for schedule(static) if (parallel_elements) num_threads(threads) \
    reduction(||: suspect)
  // clang-format on
  for (int k = 0; k < count; ++k) {
    const int i = moving_[k];
    Element& e = elements_[i];
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
    // the full inertia of a cylinder, and its attitude quaternion turns as a free top over the
    // step (free_top_turn(); unit quaternions never drift into a non-rotation, unlike the attitude
    // matrix of eq. 2).
    e.angular_momentum += torque_[moving_[k]] * dt;
    if (e.kind == ElementKind::kSphere) {
      e.angular_velocity = e.angular_momentum / e.inertia_body.x();
      // No attitude (orientation() in dem_world.hpp): turning it cost 8 % of a packed bed's step.
      e.sweep += e.velocity.norm() * dt;
    } else {
      const Eigen::Matrix3d r = e.orientation.toRotationMatrix();
      e.angular_velocity = r * (r.transpose() * e.angular_momentum).cwiseQuotient(e.inertia_body);
      const double angle = e.angular_velocity.norm() * dt;
      e.sweep += e.velocity.norm() * dt + e.half_length * angle;
      if (angle > 0.0) {
        e.orientation =
            free_top_turn(e.orientation, e.angular_momentum, e.axis, e.inertia_body, dt);
        e.axis = e.orientation * Eigen::Vector3d::UnitZ();
      }
    }
    if (!parallel_elements) {
      // The two largest sweeps for update_list_if_needed(), which then need not walk the
      // elements again (the same values as its own pass).
      if (e.sweep > largest) {
        second = largest;
        largest = e.sweep;
      } else if (e.sweep > second) {
        second = e.sweep;
      }
    }
    if (keep_hot) {
      hot_position_[i].local = e.local;
      hot_position_[i].cell = e.cell;
      hot_velocity_[i] = {e.velocity, e.angular_velocity};
    }
    // The conditions of check_stability() as one conservative test on the same values: a
    // component that is not finite makes the sum not finite (a finite sum that overflows only
    // runs the full check for nothing), and a NaN position fails both comparisons.
    // position() is this sum.
    const Eigen::Vector3d p = e.cell.cast<double>() * size + e.local;
    const double sum = e.local.sum() + e.velocity.sum() + e.angular_momentum.sum();
    if (!std::isfinite(sum) || !(p.array() >= domain_min.array()).all() ||
        !(p.array() <= domain_max.array()).all()) {
      suspect = true;
    }
  }
  sweep_largest_ = largest;
  sweep_second_ = second;
  sweep_top_valid_ = !parallel_elements;
  return suspect;
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
  const bool suspect = integrate(dt, false);
  time_ += dt;
  ++step_count_;
  if (suspect) check_stability();
}

}  // namespace cosim::dem
