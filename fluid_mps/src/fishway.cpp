#include "cosim/fluid_mps/fishway.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>

#include "cosim/fluid_mps/observers.hpp"

namespace cosim::mps {
namespace {

int cells(double length, double l0) {
  return static_cast<int>(std::lround(length / l0));
}

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("fishway: " + what);
}

// Cell layout of a scene: `solid(ix, iy)` says which cells are boundary; solid cells within
// wall_layers (Chebyshev distance, in cells) of an open cell become wall particles, the next
// dummy_layers become dummy particles, deeper ones are left out. So every face that water can
// touch (bed, risers, partitions, apron end) gets pressure-carrying walls backed by dummies.
struct CellBox {
  int x0, x1, y0, y1;  // [x0, x1) x [y0, y1)
};

void add_boundary(ParticleSet& set, double l0, const CellBox& box,
                  const std::function<bool(int, int)>& solid, int wall_layers, int dummy_layers) {
  const int reach = wall_layers + dummy_layers;
  for (int iy = box.y0; iy < box.y1; ++iy) {
    for (int ix = box.x0; ix < box.x1; ++ix) {
      if (!solid(ix, iy)) continue;
      int distance = reach + 1;
      for (int dy = -reach; dy <= reach; ++dy)
        for (int dx = -reach; dx <= reach; ++dx)
          if (!solid(ix + dx, iy + dy))
            distance = std::min(distance, std::max(std::abs(dx), std::abs(dy)));
      if (distance > reach) continue;
      set.add(Eigen::Vector3d((ix + 0.5) * l0, (iy + 0.5) * l0, 0.0),
              distance <= wall_layers ? ParticleKind::wall : ParticleKind::dummy);
    }
  }
}

struct Layout {
  int pool_columns, step_rows, weir_rows, orifice_rows, partition_columns;
};

Layout layout(const MpsParameters& parameters, const FishwayGeometry& g) {
  require(parameters.dimension == 2, "2D scenes only (dimension = 2)");
  const double l0 = parameters.particle_spacing;
  Layout k{cells(g.pool_length, l0), cells(g.step_height, l0), cells(g.weir_height, l0),
           cells(g.orifice_height, l0), g.partition_columns};
  require(g.pools >= 1, "pools must be at least 1");
  require(k.partition_columns >= 1, "partition_columns must be at least 1");
  require(k.pool_columns >= k.partition_columns + 8, "pool_length too short for l0");
  require(k.weir_rows >= 4, "weir_height must be at least 4 l0");
  require(k.orifice_rows < k.weir_rows - 2, "orifice_height must stay 2 l0 below the crest");
  require(k.step_rows >= 0, "step_height must be >= 0");
  return k;
}

// Thin-wall segment along the middle of the partition whose columns end at end_column, from its
// foot (or the orifice top) to its crest; and the weir gauge for it.
void add_weir(MpsParameters& parameters, std::vector<Weir>& weirs, const Layout& k, double l0,
              int end_column, int floor_row, double gauge_distance) {
  const double x = (end_column - 0.5 * k.partition_columns) * l0;
  const double foot = (floor_row + k.orifice_rows) * l0 - (k.orifice_rows > 0 ? 0.0 : l0);
  const double crest = (floor_row + k.weir_rows) * l0;
  parameters.partitions.push_back(PartitionSegment{{x, foot}, {x, crest}, true});
  weirs.push_back(Weir{{x, crest},
                       x - gauge_distance,
                       k.weir_rows * l0,
                       floor_row * l0,
                       (floor_row + k.orifice_rows) * l0});
}

}  // namespace

ParticleSet pool_fishway(MpsParameters& parameters, OpenBoundarySettings& inflow,
                         const FishwayGeometry& g, std::vector<Weir>& weirs, int wall_layers,
                         int dummy_layers) {
  const Layout k = layout(parameters, g);
  const double l0 = parameters.particle_spacing;
  const int pools = g.pools, layers = wall_layers + dummy_layers;
  const int block_rows = cells(g.block_height, l0), outlet_columns = cells(g.outlet_length, l0);
  require(block_rows > k.weir_rows + cells(g.initial_head, l0),
          "block_height must exceed weir_height + initial_head");
  require(g.block_columns >= 1 && g.pool_particles >= block_rows, "block and pool sizes");
  const int first_column = -(g.block_columns + 2),
            end_column = pools * k.pool_columns + outlet_columns;
  auto pool_of = [&](int ix) { return std::clamp(ix / k.pool_columns, 0, pools); };
  auto floor_row = [&](int ix) { return ix < 0 ? 0 : -pool_of(ix) * k.step_rows; };
  auto solid = [&](int ix, int iy) {
    if (ix < first_column) return true;  // nothing behind the inflow block
    if (ix >= end_column) return false;  // free overfall
    const int floor = floor_row(ix);
    if (iy < floor) return true;
    const int pool = pool_of(ix);
    if (pool < pools && ix >= (pool + 1) * k.pool_columns - k.partition_columns) {
      return iy >= floor + k.orifice_rows && iy < floor + k.weir_rows;
    }
    return false;
  };
  ParticleSet set;
  // Still water up to initial_head above every crest.
  const int level_rows = k.weir_rows + cells(g.initial_head, l0);
  for (int ix = 0; ix < pools * k.pool_columns; ++ix)
    for (int iy = floor_row(ix); iy < floor_row(ix) + level_rows; ++iy)
      if (!solid(ix, iy))
        set.add(Eigen::Vector3d((ix + 0.5) * l0, (iy + 0.5) * l0, 0.0), ParticleKind::fluid);
  // Soluble moving wall block upstream of x = 0 (seed 001 section 2.2(3)).
  for (int c = 0; c < g.block_columns; ++c)
    for (int r = 0; r < block_rows; ++r)
      set.add(Eigen::Vector3d(-(c + 0.5) * l0, (r + 0.5) * l0, 0.0), ParticleKind::wall);
  const int lowest = -pools * k.step_rows;
  add_boundary(set, l0, CellBox{first_column, end_column, lowest - layers - 1, k.weir_rows + 1},
               solid, wall_layers, dummy_layers);
  for (int pool = 0; pool < pools; ++pool) {
    add_weir(parameters, weirs, k, l0, (pool + 1) * k.pool_columns, -pool * k.step_rows,
             g.pool_length / 3.0);
  }
  inflow.inflow_x = 0.0;
  inflow.bed_height = 0.0;
  inflow.block_rows = block_rows;
  inflow.outflow_x = (end_column + 3) * l0;
  inflow.outflow_min_height = (lowest - layers - 4) * l0;
  const Eigen::Vector3d park(inflow.outflow_x + l0, inflow.outflow_min_height - 2.0 * l0, 0.0);
  for (int i = 0; i < g.pool_particles; ++i) set.add(park, ParticleKind::inactive);
  if (parameters.domain.isEmpty()) {
    parameters.domain = Eigen::AlignedBox3d(
        Eigen::Vector3d((first_column - layers - 4) * l0, inflow.outflow_min_height - 6.0 * l0,
                        -l0),
        Eigen::Vector3d(inflow.outflow_x + 4.0 * l0, 2.0 * block_rows * l0 + 10.0 * l0, l0));
  }
  return set;
}

ParticleSet periodic_pool(MpsParameters& parameters, const FishwayGeometry& g, double fill_level,
                          std::vector<Weir>& weirs, int wall_layers, int dummy_layers) {
  const Layout k = layout(parameters, g);
  const double l0 = parameters.particle_spacing;
  const int fill_rows = cells(fill_level, l0), layers = wall_layers + dummy_layers;
  require(fill_rows >= k.weir_rows, "fill_level must reach the crest");
  const int columns = k.pool_columns, drop = k.step_rows;
  // The pool's own cells; its copies up- and downstream are `drop` rows higher and lower, so the
  // riser under the partition faces the next pool's water and gets walls of its own.
  std::function<bool(int, int)> solid = [&](int ix, int iy) {
    if (ix >= columns) return solid(ix - columns, iy + drop);
    if (ix < 0) return solid(ix + columns, iy - drop);
    if (iy < 0) return true;
    return ix >= columns - k.partition_columns && iy >= k.orifice_rows && iy < k.weir_rows;
  };
  ParticleSet set;
  for (int ix = 0; ix < columns; ++ix)
    for (int iy = 0; iy < fill_rows; ++iy)
      if (!solid(ix, iy))
        set.add(Eigen::Vector3d((ix + 0.5) * l0, (iy + 0.5) * l0, 0.0), ParticleKind::fluid);
  add_boundary(set, l0, CellBox{0, columns, -drop - layers - 1, k.weir_rows + 1}, solid,
               wall_layers, dummy_layers);
  parameters.periodic.enabled = true;
  parameters.periodic.x_min = 0.0;
  parameters.periodic.x_max = columns * l0;
  parameters.periodic.drop = drop * l0;
  add_weir(parameters, weirs, k, l0, columns, 0, g.pool_length / 3.0);
  if (parameters.domain.isEmpty()) {
    parameters.domain =
        Eigen::AlignedBox3d(Eigen::Vector3d(-l0, -(drop + layers + 4) * l0, -l0),
                            Eigen::Vector3d((columns + 1) * l0, 3.0 * fill_level + 10.0 * l0, l0));
  }
  return set;
}

double rehbock_discharge(double head, double crest_height, double gravity) {
  if (head <= 0.0) return 0.0;
  const double coefficient = 0.611 + 0.08 * head / crest_height;
  return 2.0 / 3.0 * coefficient * std::sqrt(2.0 * gravity) * std::pow(head, 1.5);
}

double rehbock_head(double discharge, double crest_height, double gravity) {
  if (discharge <= 0.0) return 0.0;
  double head = std::pow(discharge / (2.0 / 3.0 * 0.611 * std::sqrt(2.0 * gravity)), 2.0 / 3.0);
  for (int iteration = 0; iteration < 100; ++iteration) {  // C_d(h) changes slowly: converges
    const double coefficient = 0.611 + 0.08 * head / crest_height;
    head = std::pow(discharge / (2.0 / 3.0 * coefficient * std::sqrt(2.0 * gravity)), 2.0 / 3.0);
  }
  return head;
}

WeirGauges::WeirGauges(std::vector<Weir> weirs, double band, double gauge_width)
    : weirs_(std::move(weirs)),
      band_(band),
      gauge_width_(gauge_width),
      discharge_sum_(weirs_.size(), 0.0),
      head_sum_(weirs_.size(), 0.0),
      orifice_sum_(weirs_.size(), 0.0),
      last_discharge_(weirs_.size(), 0.0),
      last_head_(weirs_.size(), 0.0) {
  if (!(band > 0.0) || !(gauge_width > 0.0)) {
    throw std::invalid_argument("WeirGauges: band and gauge width must be positive");
  }
}

void WeirGauges::record(const FluidSystem& system) {
  const MpsParameters& p = system.parameters();
  const double area = std::pow(p.particle_spacing, 2);
  const Eigen::Vector2d up = -p.gravity.head<2>().normalized();
  for (std::size_t w = 0; w < weirs_.size(); ++w) {
    const Weir& weir = weirs_[w];
    last_discharge_[w] = discharge_through_line(system, weir.crest.x(), weir.crest.y(),
                                                std::numeric_limits<double>::infinity(), band_);
    if (weir.orifice_top > weir.floor) {
      orifice_sum_[w] +=
          discharge_through_line(system, weir.crest.x(), weir.floor, weir.orifice_top, band_);
    }
    // Water surface above the gauge: fluid above the crest in the gauge band, as a thickness.
    int above = 0;
    for (int i = 0; i < system.particle_count(); ++i) {
      if (system.kinds()[i] != ParticleKind::fluid) continue;
      const Eigen::Vector3d& x = system.positions()[i];
      const double dx = p.periodic.wrap(Eigen::Vector3d(x.x() - weir.gauge_x, 0.0, 0.0)).x();
      if (x.y() > weir.crest.y() && std::abs(dx) < 0.5 * gauge_width_) ++above;
    }
    const double thickness = above * area / gauge_width_;
    // As an elevation difference from the crest along `up` (exact also under tilted gravity).
    const double along =
        p.periodic.wrap(Eigen::Vector3d(weir.gauge_x - weir.crest.x(), 0.0, 0.0)).x();
    last_head_[w] = up.x() * along + up.y() * thickness;
    discharge_sum_[w] += last_discharge_[w];
    head_sum_[w] += last_head_[w];
  }
  ++samples_;
}

double WeirGauges::mean_discharge(std::size_t weir) const {
  return samples_ > 0 ? discharge_sum_.at(weir) / samples_ : 0.0;
}

double WeirGauges::mean_orifice_discharge(std::size_t weir) const {
  return samples_ > 0 ? orifice_sum_.at(weir) / samples_ : 0.0;
}

double WeirGauges::mean_head(std::size_t weir) const {
  return samples_ > 0 ? head_sum_.at(weir) / samples_ : 0.0;
}

}  // namespace cosim::mps
