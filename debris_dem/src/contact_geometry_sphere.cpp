// Sphere contacts of seed 004 table 1: cases 1 (sphere-sphere), 2 (cylinder side), 3-1 and 3-2
// (cylinder base face and rim) and 4 (triangle face, edge, vertex).
#include <algorithm>
#include <cmath>

#include "cosim/debris_dem/contact_geometry.hpp"

namespace cosim::dem {
namespace {

// Any vector orthogonal to n, for the degenerate case of coincident centers.
Eigen::Vector3d any_unit_normal_to(const Eigen::Vector3d& n) {
  const Eigen::Vector3d trial =
      std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  return n.cross(trial).normalized();
}

}  // namespace

ContactGeometry sphere_cylinder(const Eigen::Vector3d& sphere_center, double sphere_radius,
                                const Eigen::Vector3d& axis, double cylinder_radius,
                                double half_length) {
  ContactGeometry g;
  // Eq. (14)-(15): reference point P on the axis, radial vector from P to the sphere.
  const double t = sphere_center.dot(axis);
  const Eigen::Vector3d radial = sphere_center - t * axis;
  const double rho = radial.norm();
  const Eigen::Vector3d radial_unit =
      rho > 0.0 ? Eigen::Vector3d(radial / rho) : any_unit_normal_to(axis);
  const double beyond_end = std::abs(t) - half_length;  // > 0: past a base plane
  const double end_sign = t >= 0.0 ? 1.0 : -1.0;
  const Eigen::Vector3d end_normal = end_sign * axis;

  if (beyond_end <= 0.0) {
    // Within the axial extent. Eq. (16) side contact; if the center is inside the cylinder push
    // it out through whichever surface (side or base) is nearer.
    const double side_overlap = sphere_radius + cylinder_radius - rho;
    if (side_overlap < 0.0) return g;
    const double base_overlap = sphere_radius - beyond_end;  // beyond_end <= 0
    g.touching = true;
    if (rho < cylinder_radius && base_overlap < side_overlap) {
      g.feature = ContactFeature::kCylinderBaseFace;
      g.overlap = base_overlap;
      g.normal = end_normal;
      g.point = radial + end_sign * (half_length - 0.5 * g.overlap) * axis;
    } else {
      g.feature = ContactFeature::kCylinderSide;
      g.overlap = side_overlap;
      g.normal = radial_unit;
      g.point = t * axis + (cylinder_radius - 0.5 * g.overlap) * radial_unit;
    }
    g.index = t >= 0.0 ? 0 : 1;
    return g;
  }
  g.index = t >= 0.0 ? 0 : 1;
  const Eigen::Vector3d base_center = end_sign * half_length * axis;  // eq. (17)
  if (rho <= cylinder_radius) {
    // Eq. (21) case-1 and (22): the foot P of the sphere on the base plane lies on the face.
    if (beyond_end > sphere_radius) return g;
    g.touching = true;
    g.feature = ContactFeature::kCylinderBaseFace;
    g.overlap = sphere_radius - beyond_end;
    g.normal = end_normal;
    g.point = base_center + radial - 0.5 * g.overlap * end_normal;
    return g;
  }
  // Eq. (23)-(24) case-2: nearest point Q on the rim of the base.
  const Eigen::Vector3d rim_point = base_center + cylinder_radius * radial_unit;
  const Eigen::Vector3d d = sphere_center - rim_point;
  const double distance = d.norm();
  if (distance > sphere_radius) return g;
  g.touching = true;
  g.feature = ContactFeature::kCylinderBaseRim;
  g.overlap = sphere_radius - distance;
  g.normal = distance > 0.0 ? Eigen::Vector3d(d / distance) : end_normal;
  g.point = rim_point - 0.5 * g.overlap * g.normal;
  return g;
}

Eigen::Vector3d closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& e1,
                                          const Eigen::Vector3d& e2, int* region) {
  // Voronoi-region walk of the triangle a=0, b=e1, c=e2 (Ericson, Real-Time Collision Detection
  // 5.1.5), which also tells whether the closest feature is the face, an edge or a vertex.
  const Eigen::Vector3d& ab = e1;
  const Eigen::Vector3d& ac = e2;
  const Eigen::Vector3d& ap = p;
  const double d1 = ab.dot(ap);
  const double d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) {
    *region = 4;
    return Eigen::Vector3d::Zero();
  }
  const Eigen::Vector3d bp = p - e1;
  const double d3 = ab.dot(bp);
  const double d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) {
    *region = 5;
    return e1;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    *region = 1;
    return (d1 / (d1 - d3)) * ab;
  }
  const Eigen::Vector3d cp = p - e2;
  const double d5 = ab.dot(cp);
  const double d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) {
    *region = 6;
    return e2;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    *region = 3;
    return (d2 / (d2 - d6)) * ac;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    *region = 2;
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return e1 + w * (e2 - e1);
  }
  *region = 0;
  const double denominator = 1.0 / (va + vb + vc);
  return ab * (vb * denominator) + ac * (vc * denominator);
}

ContactGeometry sphere_triangle(const Eigen::Vector3d& sphere_center, double sphere_radius,
                                const Eigen::Vector3d& edge1, const Eigen::Vector3d& edge2,
                                const Eigen::Vector3d& normal) {
  ContactGeometry g;
  int region = 0;
  const Eigen::Vector3d q = closest_point_on_triangle(sphere_center, edge1, edge2, &region);
  const Eigen::Vector3d d = sphere_center - q;
  const double distance = d.norm();
  // Eq. (27) for the face; the same distance test covers edges and vertices.
  if (distance > sphere_radius) return g;
  g.touching = true;
  g.overlap = sphere_radius - distance;
  if (region == 0) {
    // Eq. (25)-(26): normal is the triangle normal, on the side where the center is.
    g.feature = ContactFeature::kTriangleFace;
    g.normal = sphere_center.dot(normal) >= 0.0 ? normal : Eigen::Vector3d(-normal);
  } else {
    g.feature = region <= 3 ? ContactFeature::kTriangleEdge : ContactFeature::kTriangleVertex;
    g.index = region <= 3 ? region - 1 : region - 4;
    g.normal = distance > 0.0 ? Eigen::Vector3d(d / distance) : normal;
  }
  g.point = q - 0.5 * g.overlap * g.normal;
  return g;
}

}  // namespace cosim::dem
