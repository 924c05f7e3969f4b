// Contact detection for the nine element pairings of seed 004 table 1 (plus cylinder side on a
// triangle, which the seed leaves out but a log lying on a smooth wall needs). Every function
// works in a frame whose origin is element B's anchor (sphere/cylinder center, triangle vertex
// a): the caller passes the displacement built from local origins (section 2.4(10)), so the
// small radii are never subtracted from large world coordinates.
#pragma once

#include <Eigen/Dense>
#include <cstdint>

namespace cosim::dem {

// Which feature of B (or of the pair) is touched; the contact law ignores it, the mesh filter
// and the tests use it.
enum class ContactFeature : std::uint8_t {
  kNone,
  kSphereSphere,      // table 1 case 1
  kCylinderSide,      // case 2, sphere on cylinder side
  kCylinderBaseFace,  // case 3-1
  kCylinderBaseRim,   // case 3-2
  kTriangleFace,      // case 4 inside the triangle
  kTriangleEdge,      // case 4 on an edge (index in ContactGeometry::index)
  kTriangleVertex,    // case 4 on a vertex
  kSideSide,          // case 5 (parallel axes included)
  kSideBase,          // case 6 (index 0: A's base on B's side, 1: B's base on A's side)
  kBaseBase,          // case 7
  kBaseTriangle,      // case 8
  kSideTriangle,      // cylinder side on a triangle (not in the seed)
};

struct ContactGeometry {
  bool touching = false;
  ContactFeature feature = ContactFeature::kNone;
  int index = 0;  // edge or vertex number for triangles, end number for bases
  double overlap = 0.0;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // unit, from B towards A (pushes A)
  Eigen::Vector3d point = Eigen::Vector3d::Zero();   // contact point, B-anchor frame
};

// Sphere A (center relative to B's center) on sphere B. Eq. (13). Inline: the DEM's contact
// loop calls it for every touching sphere pair.
inline ContactGeometry sphere_sphere(const Eigen::Vector3d& center_a, double radius_a,
                                     double radius_b) {
  ContactGeometry g;
  // Eq. (13): contact while the center distance is at most the sum of the radii (squared test
  // first: most candidates are apart).
  const double reach = radius_a + radius_b;
  const double distance_squared = center_a.squaredNorm();
  if (distance_squared > reach * reach) return g;
  const double distance = std::sqrt(distance_squared);
  g.touching = true;
  g.feature = ContactFeature::kSphereSphere;
  g.overlap = radius_a + radius_b - distance;
  g.normal =
      distance > 0.0 ? Eigen::Vector3d(center_a * (1.0 / distance)) : Eigen::Vector3d::UnitZ();
  // Midway through the overlap lens: B's surface point pushed in by half the overlap.
  g.point = g.normal * (radius_b - 0.5 * g.overlap);
  return g;
}

// Sphere A on cylinder B centered at the origin: side (eq. 14-16), base face (eq. 17-22) or base
// rim (eq. 23-24). A sphere center inside the cylinder is pushed out through the nearer surface.
ContactGeometry sphere_cylinder(const Eigen::Vector3d& sphere_center, double sphere_radius,
                                const Eigen::Vector3d& axis, double cylinder_radius,
                                double half_length);

// Sphere on triangle (0, edge1, edge2) with unit normal; the closest point decides face, edge or
// vertex (eq. 25-27 for the face, the edge and vertex rounding complete it). Two-sided.
ContactGeometry sphere_triangle(const Eigen::Vector3d& sphere_center, double sphere_radius,
                                const Eigen::Vector3d& edge1, const Eigen::Vector3d& edge2,
                                const Eigen::Vector3d& normal);

// Cylinder A (center relative to B's center) on cylinder B: side-side (eq. 28-31), side-base
// (eq. 32-35) and base-base (eq. 36-39). The candidate directions are scored by the exact
// support functions of both cylinders and the least overlap wins, as in a separating-axis test.
ContactGeometry cylinder_cylinder(const Eigen::Vector3d& center_a, const Eigen::Vector3d& axis_a,
                                  double radius_a, double half_length_a,
                                  const Eigen::Vector3d& axis_b, double radius_b,
                                  double half_length_b);

// Cylinder A on triangle (0, edge1, edge2): base rim into the plane (eq. 40-43) or side lying on
// the triangle.
ContactGeometry cylinder_triangle(const Eigen::Vector3d& center, const Eigen::Vector3d& axis,
                                  double radius, double half_length, const Eigen::Vector3d& edge1,
                                  const Eigen::Vector3d& edge2, const Eigen::Vector3d& normal);

// Closest point of triangle (0, e1, e2) to p; region: 0 face, 1-3 edges (01, 12, 20),
// 4-6 vertices (0, 1, 2).
Eigen::Vector3d closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& e1,
                                          const Eigen::Vector3d& e2, int* region);

// Closest points between segments p0 + s d0 (s in [-h0, h0]) and p1 + t d1 (t in [-h1, h1]),
// d unit. For parallel segments the middle of the overlapping interval is returned.
void closest_segment_parameters(const Eigen::Vector3d& p0, const Eigen::Vector3d& d0, double h0,
                                const Eigen::Vector3d& p1, const Eigen::Vector3d& d1, double h1,
                                double* s, double* t);

// Support value max_x x.n over a cylinder (center c, unit axis a).
double cylinder_support(const Eigen::Vector3d& c, const Eigen::Vector3d& a, double radius,
                        double half_length, const Eigen::Vector3d& n);

}  // namespace cosim::dem
