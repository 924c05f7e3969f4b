// Scene builders of the open and periodic boundaries (boundaries.hpp).
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "cosim/fluid_mps/boundaries.hpp"

namespace cosim::mps {
namespace {

int cells(double length, double l0) {
  return static_cast<int>(std::lround(length / l0));
}

// Bed columns ix in [first, last), rows -1 .. -(wall + dummy) below y = 0.
void add_bed(ParticleSet& set, double l0, int first, int last, int wall_layers, int dummy_layers) {
  for (int layer = 1; layer <= wall_layers + dummy_layers; ++layer) {
    const ParticleKind kind = layer <= wall_layers ? ParticleKind::wall : ParticleKind::dummy;
    for (int ix = first; ix < last; ++ix) {
      set.add(Eigen::Vector3d((ix + 0.5) * l0, (0.5 - layer) * l0, 0.0), kind);
    }
  }
}

// Bed slope sin(theta) as a gravity tilt: g = |g| (sin theta, -cos theta), flow along +x.
void tilt_gravity(MpsParameters& parameters, double slope) {
  if (std::abs(slope) >= 1.0) throw std::invalid_argument("channel scenes: |slope| < 1");
  if (slope == 0.0) return;
  const double g = parameters.gravity.norm();
  parameters.gravity = Eigen::Vector3d(g * slope, -g * std::sqrt(1.0 - slope * slope), 0.0);
}

void require_2d(const MpsParameters& p) {
  if (p.dimension != 2) {
    throw std::invalid_argument("periodic_channel, open_channel: dimension = 2 (3D: the _3d ones)");
  }
}

void require_3d(const MpsParameters& p, const Channel3d& channel) {
  if (p.dimension != 3) throw std::invalid_argument("3D channel scenes need dimension = 3");
  if (channel.wall_layers < 1 || channel.dummy_layers < 0) {
    throw std::invalid_argument("3D channel scenes: at least one wall layer, no negative dummies");
  }
  if (cells(channel.width, p.particle_spacing) < 1) {
    throw std::invalid_argument("3D channel scenes: the width must hold at least one cell l0");
  }
}

// The bed (z < 0) and side walls (y < 0, y > width; up to wall_height) of a 3D channel over the
// cell columns ix in [first, last): a cell (iy, iz) outside the channel's open section
// (0 <= iy < ny, iz >= 0) is wall within wall_layers cells (Chebyshev distance, as tank_3d),
// dummy within wall_layers + dummy_layers, left out beyond. In the order z, y, x.
void add_channel_walls_3d(ParticleSet& set, double l0, const Channel3d& channel, int first,
                          int last) {
  const int ny = cells(channel.width, l0), nz = cells(channel.wall_height, l0);
  const int layers = channel.wall_layers + channel.dummy_layers;
  for (int iz = -layers; iz < nz; ++iz) {
    for (int iy = -layers; iy < ny + layers; ++iy) {
      const int dy = iy < 0 ? -iy : std::max(0, iy - ny + 1);
      const int distance = std::max(dy, iz < 0 ? -iz : 0);
      if (distance == 0) continue;
      const ParticleKind kind =
          distance <= channel.wall_layers ? ParticleKind::wall : ParticleKind::dummy;
      for (int ix = first; ix < last; ++ix) {
        set.add(Eigen::Vector3d((ix + 0.5) * l0, (iy + 0.5) * l0, (iz + 0.5) * l0), kind);
      }
    }
  }
}

// Particles of `kind` filling the cells ix in [first, last), iy in [0, ny), iz in [0, rows).
void add_block_3d(ParticleSet& set, double l0, int first, int last, int ny, int rows,
                  ParticleKind kind) {
  for (int iz = 0; iz < rows; ++iz)
    for (int iy = 0; iy < ny; ++iy)
      for (int ix = first; ix < last; ++ix)
        set.add(Eigen::Vector3d((ix + 0.5) * l0, (iy + 0.5) * l0, (iz + 0.5) * l0), kind);
}

// The outlet's bed line in the channel frame (x along the tilted bed, y normal to it): from
// a = (length, 0) the level bed along the world's horizontal, (cos theta, sin theta) in this
// frame, to b; then the 1:1 slope along horizontal + vertical (-sin theta, cos theta) to the
// crest c. sin theta = g_x / |g| (tilt_gravity).
struct OutletLine {
  Eigen::Vector3d a, b, c;
  // Height of the bed surface at x in [a.x, c.x] [m].
  double surface(double x) const {
    if (x <= b.x())
      return b.x() > a.x() ? a.y() + (x - a.x()) * (b.y() - a.y()) / (b.x() - a.x()) : a.y();
    return b.y() + (x - b.x()) * (c.y() - b.y()) / (c.x() - b.x());
  }
};

OutletLine outlet_line(const MpsParameters& parameters, double length, const ChannelOutlet& o) {
  const double sine = parameters.gravity.x() / parameters.gravity.norm();
  const double cosine = std::sqrt(1.0 - sine * sine);
  const Eigen::Vector3d horizontal(cosine, sine, 0.0), vertical(-sine, cosine, 0.0);
  OutletLine line;
  line.a = Eigen::Vector3d(length, 0.0, 0.0);
  line.b = line.a + o.flat_length * horizontal;
  line.c = line.b + o.slope_height * (horizontal + vertical);
  return line;
}

}  // namespace

Eigen::Vector3d outlet_crest(const MpsParameters& parameters, double length,
                             const ChannelOutlet& outlet) {
  if (outlet.empty()) return Eigen::Vector3d(length, 0.0, 0.0);
  return outlet_line(parameters, length, outlet).c;
}

ParticleSet periodic_channel(MpsParameters& parameters, double length, double depth, double slope,
                             int wall_layers, int dummy_layers) {
  require_2d(parameters);
  tilt_gravity(parameters, slope);
  const double l0 = parameters.particle_spacing;
  const int nx = cells(length, l0), ny = cells(depth, l0);
  ParticleSet set;
  for (int iy = 0; iy < ny; ++iy)
    for (int ix = 0; ix < nx; ++ix)
      set.add(Eigen::Vector3d((ix + 0.5) * l0, (iy + 0.5) * l0, 0.0), ParticleKind::fluid);
  add_bed(set, l0, 0, nx, wall_layers, dummy_layers);
  parameters.periodic.enabled = true;
  parameters.periodic.x_min = 0.0;
  parameters.periodic.x_max = nx * l0;
  if (parameters.domain.isEmpty()) {
    const int layers = wall_layers + dummy_layers;
    parameters.domain =
        Eigen::AlignedBox3d(Eigen::Vector3d(-l0, -(layers + 2) * l0, -l0),
                            Eigen::Vector3d((nx + 1) * l0, 3.0 * depth + 10.0 * l0, l0));
  }
  return set;
}

ParticleSet open_channel(MpsParameters& parameters, OpenBoundarySettings& settings, double length,
                         double initial_depth, double block_height, int block_columns,
                         int pool_particles, int wall_layers, int dummy_layers, double slope,
                         const ChannelOutlet& outlet) {
  require_2d(parameters);
  tilt_gravity(parameters, slope);
  const double l0 = parameters.particle_spacing;
  const int nx = cells(length, l0), ny = cells(initial_depth, l0);
  const int rows = cells(block_height, l0);
  const int layers = wall_layers + dummy_layers;
  if (rows < 1 || block_columns < 1) throw std::invalid_argument("open_channel: empty block");
  ParticleSet set;
  for (int iy = 0; iy < ny; ++iy)
    for (int ix = 0; ix < nx; ++ix)
      set.add(Eigen::Vector3d((ix + 0.5) * l0, (iy + 0.5) * l0, 0.0), ParticleKind::fluid);
  // Soluble moving wall block just upstream of the inflow line x = 0 (seed 001 section 2.2(3)).
  for (int c = 0; c < block_columns; ++c)
    for (int r = 0; r < rows; ++r)
      set.add(Eigen::Vector3d(-(c + 0.5) * l0, (r + 0.5) * l0, 0.0), ParticleKind::wall);
  add_bed(set, l0, -(block_columns + 2), nx, wall_layers, dummy_layers);
  // The last column of the channel, nx - 1 without an outlet, that of the crest with one.
  int end_column = nx - 1;
  if (!outlet.empty()) {
    const OutletLine line = outlet_line(parameters, length, outlet);
    if (!(line.c.x() > line.a.x())) {
      throw std::invalid_argument("open_channel: the outlet's crest must lie downstream");
    }
    // Solid: the channel bed (y < 0) up to x = length, the outlet's bed and slope under their
    // line up to the crest, the ground below the bottom dummy row everywhere (so that the
    // crest's vertical face ends there and no wall lines the bottom of the bed).
    auto solid = [&](int ix, int iy) {
      const double x = (ix + 0.5) * l0, y = (iy + 0.5) * l0;
      if (iy < -layers) return true;
      if (x < length) return y < 0.0;
      return x <= line.c.x() && y < line.surface(x);
    };
    end_column = static_cast<int>(std::floor(line.c.x() / l0));
    const int top = static_cast<int>(std::ceil(std::max(line.b.y(), line.c.y()) / l0));
    // Solid cells within wall_layers (Chebyshev distance, cells) of an open cell are walls, the
    // next dummy_layers dummies, deeper ones left out (as fishway.cpp).
    for (int iy = -layers; iy <= top; ++iy) {
      for (int ix = nx; ix <= end_column + layers; ++ix) {
        if (!solid(ix, iy)) continue;
        int distance = layers + 1;
        for (int dy = -layers; dy <= layers; ++dy)
          for (int dx = -layers; dx <= layers; ++dx)
            if (!solid(ix + dx, iy + dy))
              distance = std::min(distance, std::max(std::abs(dx), std::abs(dy)));
        if (distance > layers) continue;
        set.add(Eigen::Vector3d((ix + 0.5) * l0, (iy + 0.5) * l0, 0.0),
                distance <= wall_layers ? ParticleKind::wall : ParticleKind::dummy);
      }
    }
    // Still water over the outlet to the same depth, in its open cells upstream of the crest.
    for (int iy = 0; iy < ny; ++iy)
      for (int ix = nx; ix <= end_column; ++ix)
        if (!solid(ix, iy) && (ix + 0.5) * l0 < line.c.x())
          set.add(Eigen::Vector3d((ix + 0.5) * l0, (iy + 0.5) * l0, 0.0), ParticleKind::fluid);
  }
  // Pool of recycled particles, parked under the outlet.
  const Eigen::Vector3d park((end_column + 5) * l0, -(layers + 6) * l0, 0.0);
  for (int k = 0; k < pool_particles; ++k) set.add(park, ParticleKind::inactive);
  settings.inflow_x = 0.0;
  settings.bed_height = 0.0;
  settings.block_rows = rows;
  settings.outflow_x = (end_column + 4) * l0;
  settings.outflow_min_height = -(layers + 4) * l0;
  if (parameters.domain.isEmpty()) {
    parameters.domain = Eigen::AlignedBox3d(
        Eigen::Vector3d(-(block_columns + layers + 4) * l0, -(layers + 8) * l0, -l0),
        Eigen::Vector3d((end_column + 7) * l0, 2.0 * block_height + 10.0 * l0, l0));
  }
  return set;
}

ParticleSet periodic_channel_3d(MpsParameters& parameters, const Channel3d& channel, double length,
                                double depth) {
  require_3d(parameters, channel);
  const double l0 = parameters.particle_spacing;
  const int nx = cells(length, l0), ny = cells(channel.width, l0);
  if (nx < 1) throw std::invalid_argument("periodic_channel_3d: the length must hold a cell l0");
  ParticleSet set;
  add_block_3d(set, l0, 0, nx, ny, cells(depth, l0), ParticleKind::fluid);
  add_channel_walls_3d(set, l0, channel, 0, nx);
  parameters.periodic.enabled = true;
  parameters.periodic.x_min = 0.0;
  parameters.periodic.x_max = nx * l0;
  if (parameters.domain.isEmpty()) {
    const double margin = (channel.wall_layers + channel.dummy_layers + 2) * l0;
    const double top = std::max(3.0 * depth, channel.wall_height) + 10.0 * l0;
    parameters.domain = Eigen::AlignedBox3d(Eigen::Vector3d(-l0, -margin, -margin),
                                            Eigen::Vector3d((nx + 1) * l0, ny * l0 + margin, top));
  }
  return set;
}

ParticleSet open_channel_3d(MpsParameters& parameters, OpenBoundarySettings& settings,
                            const Channel3d& channel, double length, double initial_depth,
                            double block_height, int block_columns, int pool_particles) {
  require_3d(parameters, channel);
  const double l0 = parameters.particle_spacing;
  const int nx = cells(length, l0), ny = cells(channel.width, l0);
  const int rows = cells(block_height, l0);
  const int layers = channel.wall_layers + channel.dummy_layers;
  if (nx < 1) throw std::invalid_argument("open_channel_3d: the length must hold a cell l0");
  if (rows < 1 || block_columns < 1) throw std::invalid_argument("open_channel_3d: empty block");
  ParticleSet set;
  add_block_3d(set, l0, 0, nx, ny, cells(initial_depth, l0), ParticleKind::fluid);
  // Soluble moving wall block just upstream of the inflow line x = 0 (seed 001 section 2.2(3)).
  add_block_3d(set, l0, -block_columns, 0, ny, rows, ParticleKind::wall);
  add_channel_walls_3d(set, l0, channel, -(block_columns + 2), nx);
  // Pool of recycled particles, parked under the overfall.
  const Eigen::Vector3d park((nx + 5) * l0, 0.5 * ny * l0, -(layers + 6) * l0);
  for (int k = 0; k < pool_particles; ++k) set.add(park, ParticleKind::inactive);
  settings.inflow_x = 0.0;
  settings.bed_height = 0.0;
  settings.width = ny * l0;
  settings.block_rows = rows;
  settings.outflow_x = (nx + 3) * l0;
  settings.outflow_min_height = -(layers + 4) * l0;
  if (parameters.domain.isEmpty()) {
    // Past the brink the side walls end and the falling water spreads sideways as well as
    // downstream until the outflow takes it: as far across as it falls (a free fall from
    // the block's height).
    const double margin = (layers + 2) * l0, spread = margin + 2.0 * block_height;
    const double top = std::max(2.0 * block_height, channel.wall_height) + 10.0 * l0;
    parameters.domain = Eigen::AlignedBox3d(
        Eigen::Vector3d(-(block_columns + layers + 4) * l0, -spread, -(layers + 8) * l0),
        Eigen::Vector3d((nx + 7) * l0, ny * l0 + spread, top));
  }
  return set;
}

}  // namespace cosim::mps
