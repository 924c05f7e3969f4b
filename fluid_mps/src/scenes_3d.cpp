// 3D scene builders (scenes.hpp): a tank of wall and dummy particles with solid box obstacles,
// or closed triangle surfaces (STL), filled with water boxes, on one lattice of cells l0 wide.
#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "cosim/fluid_mps/kernels.hpp"
#include "cosim/fluid_mps/scenes.hpp"

namespace cosim::mps {
namespace {

int cells(double length, double l0) {
  return static_cast<int>(std::lround(length / l0));
}

// The grid of the fill: cubic, cells l0 wide, every cell centre a particle; fcc, cells of the
// (100) layer spacing h = 2^(-1/3) l0 fitted along each axis to the far end of the water, `reach`
// (h_d = L_d / n_d, n_d = round(L_d / h), L_d the water's largest coordinate, or the tank's size
// where there is no water), so that a water box from the tank's walls, as the still-water tank's
// and the dam-break column's, keeps its size (the tank's far walls fall on the nearest layer
// instead), the centres (i, j, k) with i + j + k even the particles (half the cells: 2 h^3 = l0^3
// per particle unstretched). Wall and dummy layers keep the thickness of the cubic lattice's:
// round(layers l0 / h) fcc layers.
struct FillGrid {
  Eigen::Vector3d spacing;
  int wall_layers = 0, layers = 0;  // solved walls; walls and dummies
  bool fcc = false;
};

FillGrid fill_grid(const Tank3d& tank, double l0, MpsParameters::FillLattice lattice,
                   const Eigen::Vector3d& reach) {
  FillGrid grid{Eigen::Vector3d::Constant(l0), tank.wall_layers,
                tank.wall_layers + tank.dummy_layers, false};
  if (lattice == MpsParameters::FillLattice::cubic) return grid;
  const double h = fcc_layer_spacing_over_l0() * l0;
  const std::array<double, 3> size{tank.length, tank.width, tank.height};
  for (int d = 0; d < 3; ++d) {
    const double extent = reach[d] > 0.5 * h ? std::min(reach[d], size[d]) : size[d];
    grid.spacing[d] = extent / std::max(1, cells(extent, h));
  }
  grid.wall_layers = std::max(1, cells(tank.wall_layers * l0, h));
  grid.layers = std::max(grid.wall_layers, cells(grid.layers * l0, h));
  grid.fcc = true;
  return grid;
}

// The cells of the tank and its walls: ix in [-layers, nx + layers), likewise iy, and
// iz in [-layers, nz) (the walls end at the tank's rim; nothing above it).
class TankLattice {
 public:
  TankLattice(const Tank3d& tank, const FillGrid& grid)
      : grid_(grid),
        layers_(grid.layers),
        n_{cells(tank.length, grid.spacing[0]), cells(tank.width, grid.spacing[1]),
           cells(tank.height, grid.spacing[2])} {
    if (n_[0] < 1 || n_[1] < 1 || n_[2] < 1) {
      throw std::invalid_argument("tank_3d: the tank must be at least one cell l0 in each size");
    }
    size_[0] = n_[0] + 2 * layers_;
    size_[1] = n_[1] + 2 * layers_;
    size_[2] = n_[2] + layers_;
  }

  int count() const { return size_[0] * size_[1] * size_[2]; }
  int layers() const { return layers_; }
  // Cell index (ix, iy, iz) of the flat index k, and back; -1 outside the lattice.
  std::array<int, 3> cell(int k) const {
    return {k % size_[0] - layers_, (k / size_[0]) % size_[1] - layers_,
            k / (size_[0] * size_[1]) - layers_};
  }
  int index(int ix, int iy, int iz) const {
    const int a = ix + layers_, b = iy + layers_, c = iz + layers_;
    if (a < 0 || b < 0 || c < 0 || a >= size_[0] || b >= size_[1] || c >= size_[2]) return -1;
    return a + size_[0] * (b + size_[1] * c);
  }
  Eigen::Vector3d centre(const std::array<int, 3>& c) const {
    return {(c[0] + 0.5) * grid_.spacing[0], (c[1] + 0.5) * grid_.spacing[1],
            (c[2] + 0.5) * grid_.spacing[2]};
  }
  // Whether the cell holds a particle (every cell of the cubic lattice, half of the fcc's).
  bool site(const std::array<int, 3>& c) const {
    return !grid_.fcc || (c[0] + c[1] + c[2]) % 2 == 0;
  }
  bool inside_tank(const std::array<int, 3>& c) const {
    return c[0] >= 0 && c[0] < n_[0] && c[1] >= 0 && c[1] < n_[1] && c[2] >= 0 && c[2] < n_[2];
  }

 private:
  FillGrid grid_;
  int layers_;
  std::array<int, 3> n_, size_{};
};

bool in_any(const std::vector<Eigen::AlignedBox3d>& boxes, const Eigen::Vector3d& x) {
  for (const auto& box : boxes) {
    if (box.contains(x)) return true;
  }
  return false;
}

// Chebyshev distance in cells from every cell to the nearest open cell, up to `limit` (larger
// values mean "deeper than limit"): a breadth-first search over the 26 neighbours from all open
// cells at once, exact for the L-infinity metric.
std::vector<int> depth_into_solid(const TankLattice& lattice, const std::vector<char>& open,
                                  int limit) {
  const int unreached = std::numeric_limits<int>::max();
  std::vector<int> depth(lattice.count(), unreached);
  std::deque<int> queue;
  for (int k = 0; k < lattice.count(); ++k) {
    if (open[k]) {
      depth[k] = 0;
      queue.push_back(k);
    }
  }
  while (!queue.empty()) {
    const int k = queue.front();
    queue.pop_front();
    if (depth[k] >= limit) continue;
    const auto c = lattice.cell(k);
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int m = lattice.index(c[0] + dx, c[1] + dy, c[2] + dz);
          if (m < 0 || depth[m] != unreached) continue;
          depth[m] = depth[k] + 1;
          queue.push_back(m);
        }
  }
  return depth;
}

Eigen::AlignedBox3d bounds(const TriangleMesh& mesh) {
  Eigen::AlignedBox3d box;
  for (const auto& t : mesh) box.extend(t.a).extend(t.b).extend(t.c);
  return box;
}

// Distance along `direction` from `origin` to the triangle, or a negative number when the ray
// misses it (Moeller & Trumbore, J. Graphics Tools 2, 1997).
double ray_hit(const Triangle& t, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) {
  const Eigen::Vector3d e1 = t.b - t.a, e2 = t.c - t.a;
  const Eigen::Vector3d p = direction.cross(e2);
  const double det = e1.dot(p);
  if (std::abs(det) < 1e-300) return -1.0;  // ray parallel to the triangle's plane
  const Eigen::Vector3d s = origin - t.a;
  const double u = s.dot(p) / det;
  if (u < 0.0 || u > 1.0) return -1.0;
  const Eigen::Vector3d q = s.cross(e1);
  const double v = direction.dot(q) / det;
  if (v < 0.0 || u + v > 1.0) return -1.0;
  return e2.dot(q) / det;
}

void require_3d(const MpsParameters& p, const char* builder) {
  if (p.dimension != 3) {
    throw std::invalid_argument(std::string(builder) + " needs dimension = 3");
  }
}

}  // namespace

bool inside_mesh(const TriangleMesh& mesh, const Eigen::Vector3d& point) {
  // A direction of no special slope, so rays from lattice points rarely graze an edge or a
  // vertex of a mesh drawn on round coordinates.
  static const Eigen::Vector3d direction = Eigen::Vector3d(1.0, 0.3183, 0.1459).normalized();
  int crossings = 0;
  for (const auto& t : mesh) crossings += ray_hit(t, point, direction) > 0.0;
  return crossings % 2 == 1;
}

ParticleSet tank_3d(MpsParameters& parameters, const Tank3d& tank,
                    const std::vector<Eigen::AlignedBox3d>& water,
                    const std::vector<TriangleMesh>& solids) {
  require_3d(parameters, "tank_3d");
  if (tank.wall_layers < 1 || tank.dummy_layers < 0) {
    throw std::invalid_argument("tank_3d: at least one wall layer, no negative dummy layers");
  }
  const double l0 = parameters.particle_spacing;
  Eigen::Vector3d reach = Eigen::Vector3d::Zero();  // the water's far end along each axis
  for (const auto& box : water) reach = reach.cwiseMax(box.max());
  const FillGrid grid = fill_grid(tank, l0, parameters.fill_lattice, reach);
  const TankLattice lattice(tank, grid);
  std::vector<Eigen::AlignedBox3d> mesh_boxes;  // to skip the ray test far from a mesh
  for (const auto& mesh : solids) mesh_boxes.push_back(bounds(mesh));
  std::vector<char> open(lattice.count(), 0);
  for (int k = 0; k < lattice.count(); ++k) {
    const auto c = lattice.cell(k);
    const Eigen::Vector3d x = lattice.centre(c);
    bool solid = !lattice.inside_tank(c) || in_any(tank.obstacles, x);
    for (std::size_t m = 0; m < solids.size() && !solid; ++m) {
      solid = mesh_boxes[m].contains(x) && inside_mesh(solids[m], x);
    }
    open[k] = !solid;
  }
  const std::vector<int> depth = depth_into_solid(lattice, open, lattice.layers());
  // One pass in the order z, y, x (particles of a layer together, as the 2D builders).
  ParticleSet set;
  for (int k = 0; k < lattice.count(); ++k) {
    const auto c = lattice.cell(k);
    if (!lattice.site(c)) continue;
    const Eigen::Vector3d x = lattice.centre(c);
    if (open[k]) {
      if (in_any(water, x)) set.add(x, ParticleKind::fluid);
    } else if (depth[k] <= grid.wall_layers) {
      set.add(x, ParticleKind::wall);
    } else if (depth[k] <= lattice.layers()) {
      set.add(x, ParticleKind::dummy);
    }
  }
  if (grid.fcc) parameters.fill_stretch = grid.spacing / (fcc_layer_spacing_over_l0() * l0);
  if (parameters.domain.isEmpty()) {
    const double margin = (tank.wall_layers + tank.dummy_layers + 2) * l0;
    parameters.domain = Eigen::AlignedBox3d(
        Eigen::Vector3d(-margin, -margin, -margin),
        Eigen::Vector3d(tank.length + margin, tank.width + margin, 2.0 * tank.height));
  }
  return set;
}

ParticleSet dam_break_3d(MpsParameters& parameters, double column_length, double column_height,
                         double tank_length, double tank_width, double tank_height, int wall_layers,
                         int dummy_layers) {
  require_3d(parameters, "dam_break_3d");
  const Tank3d tank{tank_length, tank_width, tank_height, {}, wall_layers, dummy_layers};
  const Eigen::AlignedBox3d column(Eigen::Vector3d::Zero(),
                                   Eigen::Vector3d(column_length, tank_width, column_height));
  return tank_3d(parameters, tank, {column});
}

ParticleSet still_water_tank_3d(MpsParameters& parameters, double length, double width,
                                double depth, double tank_height, int wall_layers,
                                int dummy_layers) {
  require_3d(parameters, "still_water_tank_3d");
  const Tank3d tank{length, width, tank_height, {}, wall_layers, dummy_layers};
  const Eigen::AlignedBox3d water(Eigen::Vector3d::Zero(), Eigen::Vector3d(length, width, depth));
  return tank_3d(parameters, tank, {water});
}

Tank3d spheric_test2_tank(int wall_layers, int dummy_layers) {
  Tank3d tank{3.22, 1.0, 1.0, {}, wall_layers, dummy_layers};
  tank.obstacles.emplace_back(Eigen::Vector3d(0.6635, 0.2955, 0.0),
                              Eigen::Vector3d(0.8245, 0.6985, 0.161));
  return tank;
}

ParticleSet spheric_test2(MpsParameters& parameters, int wall_layers, int dummy_layers) {
  const Tank3d tank = spheric_test2_tank(wall_layers, dummy_layers);
  const Eigen::AlignedBox3d column(Eigen::Vector3d(1.992, 0.0, 0.0),
                                   Eigen::Vector3d(3.22, 1.0, 0.55));
  return tank_3d(parameters, tank, {column});
}

}  // namespace cosim::mps
