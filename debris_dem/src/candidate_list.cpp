#include "candidate_list.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>

#include "cosim/debris_dem/contact_geometry.hpp"

namespace cosim::dem {
namespace {

using Element = DemWorld::Element;

PairKind kind_of(ElementKind a, ElementKind b) {
  if (b == ElementKind::kTriangle) {
    return a == ElementKind::kSphere ? PairKind::kSphereTriangle : PairKind::kCylinderTriangle;
  }
  if (a == ElementKind::kSphere) {
    return b == ElementKind::kSphere ? PairKind::kSphereSphere : PairKind::kSphereCylinder;
  }
  return PairKind::kCylinderCylinder;
}

ContactPair make_pair(const DemWorld& world, int a, int b) {
  const auto& elements = world.elements();
  const auto& materials = world.materials();
  // Sphere before cylinder before triangle, so each kernel sees its argument order.
  if (static_cast<int>(elements[a].kind) > static_cast<int>(elements[b].kind) ||
      (elements[a].kind == elements[b].kind && a > b)) {
    std::swap(a, b);
  }
  const Element& ea = elements[a];
  const Element& eb = elements[b];
  const Material& ma = materials[ea.material];
  const Material& mb = materials[eb.material];
  const PairConstants c = pair_constants(
      ma.normal_stiffness, mb.normal_stiffness, ma.tangential_stiffness, mb.tangential_stiffness,
      world.damping_ratio(ea.material), world.damping_ratio(eb.material), ma.friction, mb.friction,
      ea.fixed ? 0.0 : ea.mass, eb.fixed ? 0.0 : eb.mass);
  ContactPair p;
  p.a = a;
  p.b = b;
  p.kind = kind_of(ea.kind, eb.kind);
  p.normal_stiffness = c.normal_stiffness;
  p.tangential_stiffness = c.tangential_stiffness;
  p.normal_damping = c.normal_damping;
  p.tangential_damping = c.tangential_damping;
  p.friction = c.friction;
  return p;
}

std::int64_t cell_key(std::int64_t x, std::int64_t y, std::int64_t z) {
  constexpr std::int64_t kOffset = 1 << 20;
  return ((x + kOffset) << 42) | ((y + kOffset) << 21) | (z + kOffset);
}

bool pair_order(const ContactPair& l, const ContactPair& r) {
  return l.a != r.a ? l.a < r.a : l.b < r.b;
}

}  // namespace

void build_candidate_pairs(const DemWorld& world, double margin, std::vector<ContactPair>& pairs,
                           std::vector<ContactPair>& triangle_pairs,
                           std::vector<int>& group_start) {
  const auto& elements = world.elements();
  const int n = static_cast<int>(elements.size());
  const int threads = std::max(1, world.parameters().threads);
  const bool parallel = threads > 1 && n > 4096;
  std::vector<int> spheres;
  std::vector<int> cylinders;
  std::vector<int> triangles;
  double max_sphere_radius = 0.0;
  for (int i = 0; i < n; ++i) {
    const Element& e = elements[i];
    if (!e.enabled) continue;
    if (e.kind == ElementKind::kSphere) {
      spheres.push_back(i);
      max_sphere_radius = std::max(max_sphere_radius, e.radius);
    } else if (e.kind == ElementKind::kCylinder) {
      cylinders.push_back(i);
    } else {
      triangles.push_back(i);
    }
  }
  std::vector<Eigen::Vector3d> positions(n);
  for (int i = 0; i < n; ++i) positions[i] = world.position(i);

  // Seed 004 eq. (44): reach measured from the cylinder axis (not from a bounding sphere), so
  // the list stays tight around logs; the world rebuilds it before a rotating log's end sweeps
  // more than the margin (DemWorld::update_list_if_needed).
  const auto near = [&](int i, int j) {
    const Element& ei = elements[i];
    const Element& ej = elements[j];
    const Eigen::Vector3d d = world.displacement(i, j);
    const double reach = ei.radius + ej.radius + margin;
    if (ei.kind == ElementKind::kSphere && ej.kind == ElementKind::kSphere) {
      return d.squaredNorm() <= reach * reach;
    }
    if (d.norm() > ei.bounding_radius + ej.bounding_radius + margin) return false;
    double s = 0.0;
    double t = 0.0;
    closest_segment_parameters(d, ei.axis, ei.half_length, Eigen::Vector3d::Zero(), ej.axis,
                               ej.half_length, &s, &t);
    return (d + s * ei.axis - t * ej.axis).squaredNorm() <= reach * reach;
  };

  // Spheres: uniform cell grid, cell = largest sphere diameter + margin, 27 neighbour cells.
  const double cell = std::max(2.0 * max_sphere_radius + margin, 1e-9);
  std::unordered_map<std::int64_t, std::vector<int>> grid;
  grid.reserve(spheres.size());
  std::vector<Eigen::Matrix<std::int64_t, 3, 1>> sphere_cell(n);
  for (const int i : spheres) {
    const Eigen::Vector3d scaled = positions[i] / cell;
    sphere_cell[i] = {static_cast<std::int64_t>(std::floor(scaled.x())),
                      static_cast<std::int64_t>(std::floor(scaled.y())),
                      static_cast<std::int64_t>(std::floor(scaled.z()))};
    grid[cell_key(sphere_cell[i].x(), sphere_cell[i].y(), sphere_cell[i].z())].push_back(i);
  }
  std::vector<ContactPair> found;
#pragma omp parallel if (parallel) num_threads(threads)
  {
    std::vector<ContactPair> local;
#pragma omp for schedule(dynamic, 256) nowait
    for (int k = 0; k < static_cast<int>(spheres.size()); ++k) {
      const int i = spheres[k];
      const auto& c = sphere_cell[i];
      for (int dx = -1; dx <= 1; ++dx) {
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dz = -1; dz <= 1; ++dz) {
            const auto it = grid.find(cell_key(c.x() + dx, c.y() + dy, c.z() + dz));
            if (it == grid.end()) continue;
            for (const int j : it->second) {
              if (j <= i || (elements[i].fixed && elements[j].fixed)) continue;
              if (near(i, j)) local.push_back(make_pair(world, i, j));
            }
          }
        }
      }
    }
    // Cylinders are few (logs, dam columns): test them against every sphere and cylinder.
#pragma omp for schedule(dynamic, 4) nowait
    for (int k = 0; k < static_cast<int>(cylinders.size()); ++k) {
      const int c = cylinders[k];
      for (const int s : spheres) {
        if (elements[c].fixed && elements[s].fixed) continue;
        if (near(c, s)) local.push_back(make_pair(world, s, c));
      }
      for (const int d : cylinders) {
        if (d <= c || (elements[c].fixed && elements[d].fixed)) continue;
        if (near(c, d)) local.push_back(make_pair(world, c, d));
      }
    }
#pragma omp critical
    found.insert(found.end(), local.begin(), local.end());
  }
  std::sort(found.begin(), found.end(), pair_order);
  pairs.swap(found);

  // Triangles against each moving element: distance from its center to the triangle.
  triangle_pairs.clear();
  group_start.clear();
  std::vector<std::vector<ContactPair>> per_element(n);
#pragma omp parallel for schedule(dynamic, 64) if (parallel) num_threads(threads)
  for (int i = 0; i < n; ++i) {
    const Element& e = elements[i];
    if (!e.enabled || e.fixed || e.kind == ElementKind::kTriangle) continue;
    for (const int t : triangles) {
      const Element& tri = elements[t];
      const Eigen::Vector3d p = world.displacement(i, t);
      int region = 0;
      const Eigen::Vector3d q = closest_point_on_triangle(p, tri.edge1, tri.edge2, &region);
      const double reach = e.bounding_radius + margin;
      if ((p - q).squaredNorm() <= reach * reach) per_element[i].push_back(make_pair(world, i, t));
    }
  }
  for (int i = 0; i < n; ++i) {
    if (per_element[i].empty()) continue;
    group_start.push_back(static_cast<int>(triangle_pairs.size()));
    triangle_pairs.insert(triangle_pairs.end(), per_element[i].begin(), per_element[i].end());
  }
  group_start.push_back(static_cast<int>(triangle_pairs.size()));
}

void carry_over_history(const std::vector<ContactPair>& old_pairs,
                        std::vector<ContactPair>& new_pairs) {
  auto it = old_pairs.begin();
  for (auto& p : new_pairs) {
    while (it != old_pairs.end() && pair_order(*it, p)) ++it;
    if (it == old_pairs.end()) return;
    if (it->a == p.a && it->b == p.b) {
      p.tangential_spring = it->tangential_spring;
      p.touching = it->touching;
      p.force_on_a = it->force_on_a;
      p.lever_a = it->lever_a;
      p.lever_b = it->lever_b;
      p.overlap = it->overlap;
      p.overlap_ratio = it->overlap_ratio;
    }
  }
}

}  // namespace cosim::dem
