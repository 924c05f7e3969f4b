#include "cosim/debris_dem/scenes.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

#include "cosim/debris_dem/contact_geometry.hpp"

namespace cosim::dem {

Eigen::Vector3d slope_gravity(double slope_degrees, double g) {
  const double angle = slope_degrees * std::numbers::pi / 180.0;
  return {g * std::sin(angle), 0.0, -g * std::cos(angle)};
}

namespace {

void add_rectangle(DemWorld& world, const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                   const Eigen::Vector3d& p2, const Eigen::Vector3d& p3, const Material& m,
                   std::vector<int>& ids) {
  ids.push_back(world.add_triangle(p0, p1, p2, m));
  ids.push_back(world.add_triangle(p0, p2, p3, m));
}

}  // namespace

std::vector<int> add_flume(DemWorld& world, const FlumeSpec& s, const Material& material) {
  std::vector<int> ids;
  const double x0 = s.x_start;
  const double x1 = s.x_start + s.length;
  const double w = s.width;
  const double h = s.wall_height;
  add_rectangle(world, {x0, 0, 0}, {x1, 0, 0}, {x1, w, 0}, {x0, w, 0}, material, ids);
  add_rectangle(world, {x0, 0, 0}, {x1, 0, 0}, {x1, 0, h}, {x0, 0, h}, material, ids);
  add_rectangle(world, {x0, w, 0}, {x1, w, 0}, {x1, w, h}, {x0, w, h}, material, ids);
  if (s.upstream_wall) {
    add_rectangle(world, {x0, 0, 0}, {x0, w, 0}, {x0, w, h}, {x0, 0, h}, material, ids);
  }
  if (s.downstream_wall) {
    add_rectangle(world, {x1, 0, 0}, {x1, w, 0}, {x1, w, h}, {x1, 0, h}, material, ids);
  }
  return ids;
}

std::vector<int> add_open_box(DemWorld& world, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                              const Material& material) {
  if ((hi - lo).minCoeff() <= 0.0) throw std::invalid_argument("add_open_box: hi must exceed lo");
  std::vector<int> ids;
  const double x0 = lo.x(), y0 = lo.y(), z0 = lo.z();
  const double x1 = hi.x(), y1 = hi.y(), z1 = hi.z();
  add_rectangle(world, {x0, y0, z0}, {x1, y0, z0}, {x1, y1, z0}, {x0, y1, z0}, material, ids);
  add_rectangle(world, {x0, y0, z0}, {x1, y0, z0}, {x1, y0, z1}, {x0, y0, z1}, material, ids);
  add_rectangle(world, {x0, y1, z0}, {x1, y1, z0}, {x1, y1, z1}, {x0, y1, z1}, material, ids);
  add_rectangle(world, {x0, y0, z0}, {x0, y1, z0}, {x0, y1, z1}, {x0, y0, z1}, material, ids);
  add_rectangle(world, {x1, y0, z0}, {x1, y1, z0}, {x1, y1, z1}, {x1, y0, z1}, material, ids);
  return ids;
}

std::vector<int> add_bed_roughness(DemWorld& world, double x0, double x1, double width,
                                   double d_min, double d_max, unsigned seed,
                                   const Material& material) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> diameter(d_min, d_max);
  std::uniform_real_distribution<double> jitter(-0.25, 0.25);
  std::vector<int> ids;
  const double spacing = d_max;
  const int nx = std::max(1, static_cast<int>(std::floor((x1 - x0) / spacing)));
  const int ny = std::max(1, static_cast<int>(std::floor(width / spacing)));
  for (int i = 0; i < nx; ++i) {
    for (int j = 0; j < ny; ++j) {
      const double d = diameter(rng);
      const double x = x0 + (i + 0.5 + jitter(rng)) * spacing;
      const double y = (j + 0.5 + jitter(rng)) * (width / ny);
      // Centers on the bed: half of each sphere is buried (fig. 12).
      ids.push_back(world.add_sphere({x, std::clamp(y, 0.5 * d, width - 0.5 * d), 0.0}, 0.5 * d,
                                     material, true));
    }
  }
  return ids;
}

std::vector<int> add_grid_dam(DemWorld& world, const GridDamSpec& s, const Material& material) {
  std::vector<int> ids;
  const double d = s.column_diameter;
  const double pitch = s.horizontal_gap + d;
  // Columns centred in the flume; enough of them that the gaps to the walls are no wider than
  // the clear gap (a wider wall gap would let boulders bypass the grid).
  const int columns =
      std::max(1, static_cast<int>(std::ceil((s.width - s.horizontal_gap) / pitch - 1e-9)));
  const double span = (columns - 1) * pitch;
  const double y0 = 0.5 * (s.width - span);
  for (int c = 0; c < columns; ++c) {
    ids.push_back(world.add_cylinder({s.x, y0 + c * pitch, 0.5 * s.height},
                                     Eigen::Vector3d::UnitZ(), 0.5 * d, s.height, material, true));
  }
  if (s.vertical_gap > 0.0) {
    // Horizontal beams just upstream of the columns, clear gap l_V between them and the bed.
    for (double z = s.vertical_gap + 0.5 * d; z + 0.5 * d <= s.height; z += s.vertical_gap + d) {
      ids.push_back(world.add_cylinder({s.x - d, 0.5 * s.width, z}, Eigen::Vector3d::UnitY(),
                                       0.5 * d, s.width, material, true));
    }
  }
  return ids;
}

std::vector<int> Packing::all() const {
  std::vector<int> ids = logs;
  ids.insert(ids.end(), spheres.begin(), spheres.end());
  std::sort(ids.begin(), ids.end());
  return ids;
}

Packing random_packing(DemWorld& world, const PackingSpec& s, const Material& sphere_material,
                       const Material& log_material) {
  std::mt19937 rng(s.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  struct Placed {
    Eigen::Vector3d center;
    Eigen::Vector3d axis;
    double radius;
    double half_length;  // 0 for spheres
  };
  std::vector<Placed> placed;
  const auto overlaps = [&](const Placed& q) {
    for (const Placed& p : placed) {
      const Eigen::Vector3d d = q.center - p.center;
      if (d.norm() > std::hypot(q.radius, q.half_length) + std::hypot(p.radius, p.half_length)) {
        continue;
      }
      ContactGeometry g;
      if (q.half_length == 0.0 && p.half_length == 0.0) {
        g = sphere_sphere(d, q.radius, p.radius);
      } else if (q.half_length == 0.0) {
        g = sphere_cylinder(d, q.radius, p.axis, p.radius, p.half_length);
      } else if (p.half_length == 0.0) {
        g = sphere_cylinder(-d, p.radius, q.axis, q.radius, q.half_length);
      } else {
        g = cylinder_cylinder(d, q.axis, q.radius, q.half_length, p.axis, p.radius, p.half_length);
      }
      if (g.touching) return true;
    }
    return false;
  };
  const auto random_point = [&](const Eigen::Vector3d& inset) {
    Eigen::Vector3d p;
    for (int k = 0; k < 3; ++k) {
      const double lo = s.box_min[k] + inset[k];
      const double hi = s.box_max[k] - inset[k];
      if (hi < lo) throw std::runtime_error("random_packing: element larger than the box");
      p[k] = lo + (hi - lo) * unit(rng);
    }
    return p;
  };
  Packing out;
  for (int i = 0; i < s.log_count; ++i) {
    bool done = false;
    for (int attempt = 0; attempt < s.attempts_per_element && !done; ++attempt) {
      const double angle = 2.0 * std::numbers::pi * unit(rng);
      const Eigen::Vector3d axis(std::cos(angle), std::sin(angle), 0.2 * (unit(rng) - 0.5));
      Placed q{Eigen::Vector3d::Zero(), axis.normalized(), 0.5 * s.log_diameter,
               0.5 * s.log_length};
      const Eigen::Vector3d extent = (q.half_length * q.axis.cwiseAbs()).array() + q.radius;
      q.center = random_point(extent);
      if (overlaps(q)) continue;
      placed.push_back(q);
      out.logs.push_back(
          world.add_cylinder(q.center, q.axis, q.radius, s.log_length, log_material));
      done = true;
    }
    if (!done) throw std::runtime_error("random_packing: could not place log " + std::to_string(i));
  }
  for (std::size_t i = 0; i < s.sphere_diameters.size(); ++i) {
    const double r = 0.5 * s.sphere_diameters[i];
    bool done = false;
    for (int attempt = 0; attempt < s.attempts_per_element && !done; ++attempt) {
      Placed q{random_point(Eigen::Vector3d::Constant(r)), Eigen::Vector3d::UnitZ(), r, 0.0};
      if (overlaps(q)) continue;
      placed.push_back(q);
      out.spheres.push_back(world.add_sphere(q.center, r, sphere_material));
      done = true;
    }
    if (!done) {
      throw std::runtime_error("random_packing: could not place sphere " + std::to_string(i) +
                               "; enlarge the box");
    }
  }
  return out;
}

double settle(DemWorld& world, double duration) {
  const double window = 1e-3;
  const int windows = std::max(1, static_cast<int>(std::ceil(duration / window)));
  for (int k = 0; k < windows; ++k) world.advance(window, {}, {});
  double fastest = 0.0;
  for (const int i : world.moving_elements()) fastest = std::max(fastest, world.velocity(i).norm());
  return fastest;
}

double capture_rate(const DemWorld& world, const std::vector<int>& debris, double x_dam) {
  double total = 0.0;
  double retained = 0.0;
  for (const int i : debris) {
    const double v = world.volume(i);
    total += v;
    if (world.position(i).x() < x_dam) retained += v;
  }
  return total > 0.0 ? retained / total : 0.0;
}

DebrisFront debris_front(const DemWorld& world, const std::vector<int>& debris, double width,
                         double bin) {
  DebrisFront f;
  if (debris.empty()) return f;
  struct Piece {
    double x, volume;
  };
  std::vector<Piece> pieces;
  double total = 0.0, low = world.position(debris.front()).x(), high = low;
  for (const int i : debris) {
    const double x = world.position(i).x();
    pieces.push_back({x, world.volume(i)});
    total += world.volume(i);
    low = std::min(low, x);
    high = std::max(high, x);
  }
  f.extent = high - low;
  std::sort(pieces.begin(), pieces.end(), [](const Piece& a, const Piece& b) { return a.x < b.x; });
  auto quantile = [&](double q) {
    double sum = 0.0;
    for (const auto& p : pieces) {
      sum += p.volume;
      if (sum >= q * total) return p.x;
    }
    return pieces.back().x;
  };
  f.tail = quantile(0.01);
  f.front = quantile(0.99);
  f.length = f.front - f.tail;
  const int bins = std::max(1, static_cast<int>(std::ceil(f.length / bin)));
  f.bin_x.resize(bins);
  f.top.assign(bins, 0.0);
  f.solid_depth.assign(bins, 0.0);
  for (int b = 0; b < bins; ++b) f.bin_x[b] = f.tail + (b + 0.5) * bin;
  const double third = f.front - f.length / 3.0;
  double logs = 0.0, logs_front = 0.0, volume_front = 0.0;
  for (const int i : debris) {
    const Eigen::Vector3d x = world.position(i);
    const bool log = world.kind(i) == ElementKind::kCylinder;
    if (log) logs += world.volume(i);
    if (x.x() >= third && x.x() <= f.front) {
      volume_front += world.volume(i);
      if (log) logs_front += world.volume(i);
    }
    if (x.x() < f.tail || x.x() > f.front) continue;
    const int b = std::min(bins - 1, static_cast<int>((x.x() - f.tail) / bin));
    // A log's highest point: its centre plus its radius and the rise of half its length.
    const double reach = log ? world.radius(i) + 0.5 * world.length(i) * std::abs(world.axis(i).z())
                             : world.radius(i);
    f.top[b] = std::max(f.top[b], x.z() + reach);
    f.solid_depth[b] += world.volume(i) / (bin * width);
  }
  // Head: the front fifth of the bins (at least one); body: the median top of the others.
  const int head_bins = std::max(1, bins / 5);
  const double head = *std::max_element(f.top.end() - head_bins, f.top.end());
  std::vector<double> body(f.top.begin(), f.top.end() - head_bins);
  if (!body.empty()) {
    std::nth_element(body.begin(), body.begin() + body.size() / 2, body.end());
    const double median = body[body.size() / 2];
    f.head_over_body = median > 0.0 ? head / median : std::nan("");
  } else {
    f.head_over_body = std::nan("");
  }
  f.log_front_enrichment = logs > 0.0 && volume_front > 0.0
                               ? (logs_front / logs) / (volume_front / total)
                               : std::nan("");
  return f;
}

void prescribed_flume_flow(const DemWorld& world, const Eigen::Vector3d& surface_velocity,
                           double depth, std::vector<Eigen::Vector3d>& velocity,
                           std::vector<double>& water_fraction) {
  const auto& moving = world.moving_elements();
  velocity.resize(moving.size());
  water_fraction.resize(moving.size());
  for (std::size_t k = 0; k < moving.size(); ++k) {
    const double z = std::max(0.0, world.position(moving[k]).z());
    const bool wet = z <= depth;
    // Eq. (50): U_i = (z_i / h) U / 5 + 4 U / 5 for 0 <= z_i <= h; no fluid force above h.
    velocity[k] =
        wet ? Eigen::Vector3d((z / depth / 5.0 + 0.8) * surface_velocity) : Eigen::Vector3d::Zero();
    water_fraction[k] = wet ? 1.0 : 0.0;
  }
}

double capture_flow_factor(double z, double depth, double dam_depth) {
  if (z < 0.0 || z > dam_depth || dam_depth <= 0.0) return 0.0;
  // Eq. (51): alpha = 1.8 h / h_D - 1, beta = 1; eq. (52): alpha >= 0.1 with beta adjusted so
  // that (alpha + beta) / 2 h_D = 0.9 h, the discharge of eq. (50).
  double alpha = 1.8 * depth / dam_depth - 1.0;
  double beta = 1.0;
  if (alpha <= 0.1) {
    alpha = 0.1;
    beta = 1.8 * depth / dam_depth - alpha;
  }
  return (beta - alpha) * z / dam_depth + alpha;  // eq. (53)
}

}  // namespace cosim::dem
