// Cylinder contacts of seed 004 table 1: cases 5 (side-side), 6 (side-base), 7 (base-base) and
// 8 (base-triangle), plus cylinder side on a triangle.
//
// The seed tests each case with its own formula (eq. 28-43). Here each formula contributes a
// candidate normal direction, and every candidate is scored with the exact support functions of
// both bodies (overlap along n = max over B of x.n - min over A of x.n). For convex bodies the
// overlap along any direction bounds the penetration depth from above and a direction with no
// overlap separates them, so the smallest score picks the active case without the case
// boundaries of the seed having to agree with each other.
#include <algorithm>
#include <array>
#include <cmath>

#include "cosim/debris_dem/contact_geometry.hpp"

namespace cosim::dem {
namespace {

constexpr double kParallelTolerance = 1.0e-9;
constexpr double kDegenerate = 1.0e-6;

// Deepest point of a cylinder in direction d. Where the support is a whole face or a whole
// generator line, the point nearest to `reference` on it is used so that the contact point sits
// over the other body, not at the cylinder's center.
Eigen::Vector3d cylinder_support_point(const Eigen::Vector3d& c, const Eigen::Vector3d& a,
                                       double radius, double half_length, const Eigen::Vector3d& d,
                                       const Eigen::Vector3d& reference) {
  const double ad = a.dot(d);
  const double axial = std::abs(ad) > kDegenerate
                           ? std::copysign(half_length, ad)
                           : std::clamp((reference - c).dot(a), -half_length, half_length);
  const Eigen::Vector3d perpendicular = d - ad * a;
  const double perpendicular_norm = perpendicular.norm();
  Eigen::Vector3d radial;
  if (perpendicular_norm > kDegenerate) {
    radial = radius * perpendicular / perpendicular_norm;
  } else {
    radial = reference - c - (reference - c).dot(a) * a;
    const double n = radial.norm();
    if (n > radius) radial *= radius / n;
  }
  return c + axial * a + radial;
}

// Interval of the axis parameter s (|s| <= h) whose points project inside the triangle along its
// normal; used to centre a line contact of a log lying on a triangle.
bool axis_interval_over_triangle(const Eigen::Vector3d& c, const Eigen::Vector3d& a, double h,
                                 const Eigen::Vector3d& e1, const Eigen::Vector3d& e2,
                                 const Eigen::Vector3d& normal, double* s0, double* s1) {
  double lo = -h;
  double hi = h;
  const std::array<Eigen::Vector3d, 3> vertices{Eigen::Vector3d::Zero(), e1, e2};
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d& p = vertices[k];
    const Eigen::Vector3d& q = vertices[(k + 1) % 3];
    const Eigen::Vector3d& opposite = vertices[(k + 2) % 3];
    Eigen::Vector3d inward = normal.cross(q - p);
    if (inward.dot(opposite - p) < 0.0) inward = -inward;
    // inward.(c + s a - p) >= 0
    const double base = inward.dot(c - p);
    const double slope = inward.dot(a);
    if (std::abs(slope) < 1e-14) {
      if (base < 0.0) return false;
      continue;
    }
    const double root = -base / slope;
    if (slope > 0.0) {
      lo = std::max(lo, root);
    } else {
      hi = std::min(hi, root);
    }
  }
  *s0 = lo;
  *s1 = hi;
  return lo <= hi;
}

}  // namespace

double cylinder_support(const Eigen::Vector3d& c, const Eigen::Vector3d& a, double radius,
                        double half_length, const Eigen::Vector3d& n) {
  const double an = a.dot(n);
  return c.dot(n) + half_length * std::abs(an) + radius * std::sqrt(std::max(0.0, 1.0 - an * an));
}

void closest_segment_parameters(const Eigen::Vector3d& p0, const Eigen::Vector3d& d0, double h0,
                                const Eigen::Vector3d& p1, const Eigen::Vector3d& d1, double h1,
                                double* s, double* t) {
  // Eq. (28)-(30): E = P_i - P_j orthogonal to both axes, then clamped to the lengths.
  const Eigen::Vector3d r = p0 - p1;
  const double b = d0.dot(d1);
  const double c = d0.dot(r);
  const double f = d1.dot(r);
  const double denominator = 1.0 - b * b;
  if (denominator < kParallelTolerance) {
    // Parallel axes: any pair on the common interval is closest; take its middle so that the
    // contact point and torque do not depend on round-off.
    const double offset = -c;  // position of p1 along d0 relative to p0
    const double sign = b >= 0.0 ? 1.0 : -1.0;
    const double lo = std::max(-h0, offset - h1);
    const double hi = std::min(h0, offset + h1);
    *s = lo <= hi ? 0.5 * (lo + hi) : std::clamp(offset, -h0, h0);
    *t = std::clamp(sign * (*s - offset), -h1, h1);
    return;
  }
  double ss = std::clamp((b * f - c) / denominator, -h0, h0);
  double tt = std::clamp(b * ss + f, -h1, h1);
  ss = std::clamp(b * tt - c, -h0, h0);
  *s = ss;
  *t = tt;
}

ContactGeometry cylinder_cylinder(const Eigen::Vector3d& center_a, const Eigen::Vector3d& axis_a,
                                  double radius_a, double half_length_a,
                                  const Eigen::Vector3d& axis_b, double radius_b,
                                  double half_length_b) {
  ContactGeometry g;
  const Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  double s = 0.0;
  double t = 0.0;
  closest_segment_parameters(center_a, axis_a, half_length_a, origin, axis_b, half_length_b, &s,
                             &t);
  const Eigen::Vector3d point_a = center_a + s * axis_a;
  const Eigen::Vector3d point_b = t * axis_b;

  struct Candidate {
    Eigen::Vector3d direction;
    ContactFeature feature;
    int index;
  };
  std::array<Candidate, 12> candidates;
  int count = 0;
  const auto add = [&](const Eigen::Vector3d& d, ContactFeature feature, int index) {
    const double n = d.norm();
    if (n > 1e-12) candidates[count++] = {d / n, feature, index};
  };
  // Case 5 (eq. 28-31): E between the closest axis points.
  const bool interior = std::abs(s) < half_length_a && std::abs(t) < half_length_b;
  add(point_a - point_b, interior ? ContactFeature::kSideSide : ContactFeature::kSideBase, 0);
  // Case 6 (eq. 32-35): from a base centre to the other axis.
  for (int end = 0; end < 2; ++end) {
    const double sign = end == 0 ? 1.0 : -1.0;
    const Eigen::Vector3d base_a = center_a + sign * half_length_a * axis_a;
    const double ta = std::clamp(base_a.dot(axis_b), -half_length_b, half_length_b);
    add(base_a - ta * axis_b, ContactFeature::kSideBase, 0);
    const Eigen::Vector3d base_b = sign * half_length_b * axis_b;
    const double tb = std::clamp((base_b - center_a).dot(axis_a), -half_length_a, half_length_a);
    add(center_a + tb * axis_a - base_b, ContactFeature::kSideBase, 1);
  }
  // Case 6 with the rim (eq. 35): from the other axis to the rim point of a base that leans
  // towards it, found by projecting D onto the base plane.
  const auto rim_towards_axis = [](const Eigen::Vector3d& base, const Eigen::Vector3d& a, double r,
                                   const Eigen::Vector3d& line_point,
                                   const Eigen::Vector3d& line_axis, double line_half) {
    Eigen::Vector3d rim = base;
    for (int iteration = 0; iteration < 2; ++iteration) {
      const double t = std::clamp((rim - line_point).dot(line_axis), -line_half, line_half);
      const Eigen::Vector3d d = line_point + t * line_axis - base;
      const Eigen::Vector3d in_plane = d - d.dot(a) * a;
      const double n = in_plane.norm();
      if (n < 1e-12) break;
      rim = base + r * in_plane / n;
    }
    const double t = std::clamp((rim - line_point).dot(line_axis), -line_half, line_half);
    return Eigen::Vector3d(rim - (line_point + t * line_axis));
  };
  for (int end = 0; end < 2; ++end) {
    const double sign = end == 0 ? 1.0 : -1.0;
    add(rim_towards_axis(center_a + sign * half_length_a * axis_a, axis_a, radius_a, origin, axis_b,
                         half_length_b),
        ContactFeature::kSideBase, 0);
    add(-rim_towards_axis(sign * half_length_b * axis_b, axis_b, radius_b, center_a, axis_a,
                          half_length_a),
        ContactFeature::kSideBase, 1);
  }
  // Case 7 (eq. 36-39): base planes.
  add(axis_a, ContactFeature::kBaseBase, 0);
  add(axis_b, ContactFeature::kBaseBase, 1);

  double best = std::numeric_limits<double>::infinity();
  int best_index = -1;
  Eigen::Vector3d best_normal = Eigen::Vector3d::Zero();
  for (int k = 0; k < count; ++k) {
    for (const double sign : {1.0, -1.0}) {
      const Eigen::Vector3d n = sign * candidates[k].direction;
      const double overlap =
          cylinder_support(origin, axis_b, radius_b, half_length_b, n) +
          cylinder_support(center_a, axis_a, radius_a, half_length_a, Eigen::Vector3d(-n));
      if (overlap < best) {
        best = overlap;
        best_index = k;
        best_normal = n;
      }
    }
  }
  if (best_index < 0 || best < 0.0) return g;
  g.touching = true;
  g.overlap = best;
  g.normal = best_normal;
  g.feature = candidates[best_index].feature;
  g.index = candidates[best_index].index;
  const Eigen::Vector3d deepest_a =
      cylinder_support_point(center_a, axis_a, radius_a, half_length_a, -best_normal, point_b);
  const Eigen::Vector3d deepest_b =
      cylinder_support_point(origin, axis_b, radius_b, half_length_b, best_normal, point_a);
  g.point = 0.5 * (deepest_a + deepest_b);
  return g;
}

ContactGeometry cylinder_triangle(const Eigen::Vector3d& center, const Eigen::Vector3d& axis,
                                  double radius, double half_length, const Eigen::Vector3d& edge1,
                                  const Eigen::Vector3d& edge2, const Eigen::Vector3d& normal) {
  ContactGeometry g;
  const std::array<Eigen::Vector3d, 3> vertices{Eigen::Vector3d::Zero(), edge1, edge2};
  // Closest pair between the axis segment and the triangle: segment ends against the face and
  // the axis against each edge.
  double best_distance = std::numeric_limits<double>::infinity();
  Eigen::Vector3d axis_point = center;
  Eigen::Vector3d triangle_point = Eigen::Vector3d::Zero();
  for (const double sign : {1.0, -1.0}) {
    const Eigen::Vector3d end = center + sign * half_length * axis;
    int region = 0;
    const Eigen::Vector3d q = closest_point_on_triangle(end, edge1, edge2, &region);
    const double d = (end - q).norm();
    if (d < best_distance) {
      best_distance = d;
      axis_point = end;
      triangle_point = q;
    }
  }
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d& p = vertices[k];
    const Eigen::Vector3d edge = vertices[(k + 1) % 3] - p;
    const double edge_half = 0.5 * edge.norm();
    const Eigen::Vector3d edge_unit = edge / (2.0 * edge_half);
    double s = 0.0;
    double u = 0.0;
    closest_segment_parameters(center, axis, half_length, p + edge_half * edge_unit, edge_unit,
                               edge_half, &s, &u);
    const Eigen::Vector3d pa = center + s * axis;
    const Eigen::Vector3d pt = p + (edge_half + u) * edge_unit;
    const double d = (pa - pt).norm();
    if (d < best_distance) {
      best_distance = d;
      axis_point = pa;
      triangle_point = pt;
    }
  }
  // Axis piercing the triangle: distance zero, the plane normal separates best.
  const double an = axis.dot(normal);
  if (std::abs(an) > 1e-12) {
    const double s = -center.dot(normal) / an;
    if (std::abs(s) <= half_length) {
      const Eigen::Vector3d pierce = center + s * axis;
      int region = 0;
      const Eigen::Vector3d q = closest_point_on_triangle(pierce, edge1, edge2, &region);
      if ((q - pierce).squaredNorm() < 1e-24 || region == 0) {
        best_distance = 0.0;
        axis_point = pierce;
        triangle_point = pierce;
      }
    }
  }

  std::array<Eigen::Vector3d, 6> directions;
  int count = 0;
  const auto add = [&](const Eigen::Vector3d& d) {
    const double n = d.norm();
    if (n > 1e-12) directions[count++] = d / n;
  };
  add(normal);                       // eq. (40)-(43): base rim into the plane
  add(axis_point - triangle_point);  // side or rim against an edge or vertex
  add(axis);
  for (int k = 0; k < 3; ++k) add(axis.cross(vertices[(k + 1) % 3] - vertices[k]));

  double best = std::numeric_limits<double>::infinity();
  Eigen::Vector3d best_normal = Eigen::Vector3d::Zero();
  for (int k = 0; k < count; ++k) {
    for (const double sign : {1.0, -1.0}) {
      const Eigen::Vector3d n = sign * directions[k];
      double triangle_max = -std::numeric_limits<double>::infinity();
      for (const auto& v : vertices) triangle_max = std::max(triangle_max, v.dot(n));
      const double overlap =
          triangle_max + cylinder_support(center, axis, radius, half_length, Eigen::Vector3d(-n));
      if (overlap < best) {
        best = overlap;
        best_normal = n;
      }
    }
  }
  if (best < 0.0 || !std::isfinite(best)) return g;
  g.touching = true;
  g.overlap = best;
  g.normal = best_normal;
  // Contact point: the cylinder's deepest point; for a log lying flat, the middle of the part
  // of its axis that lies over this triangle.
  Eigen::Vector3d reference = triangle_point;
  const double along = axis.dot(best_normal);
  if (std::abs(along) <= 1e-6) {
    double s0 = 0.0;
    double s1 = 0.0;
    if (axis_interval_over_triangle(center, axis, half_length, edge1, edge2, normal, &s0, &s1)) {
      reference = center + 0.5 * (s0 + s1) * axis;
    }
  }
  const Eigen::Vector3d deepest =
      cylinder_support_point(center, axis, radius, half_length, -best_normal, reference);
  g.point = deepest + 0.5 * g.overlap * best_normal;
  g.feature =
      std::abs(along) > 1e-6 ? ContactFeature::kBaseTriangle : ContactFeature::kSideTriangle;
  return g;
}

}  // namespace cosim::dem
