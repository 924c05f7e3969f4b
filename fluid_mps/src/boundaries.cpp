#include "cosim/fluid_mps/boundaries.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace cosim::mps {
namespace {

double cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

}  // namespace

bool crosses_partition(const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                       const PartitionSegment& segment) {
  const Eigen::Vector2d a = segment.a, b = segment.b;
  const Eigen::Vector2d p2 = p.head<2>(), q2 = q.head<2>();
  const double side_p = cross(b - a, p2 - a), side_q = cross(b - a, q2 - a);
  if (!(side_p * side_q < 0.0)) return false;  // same side or touching the partition line
  const double side_a = cross(q2 - p2, a - p2), side_b = cross(q2 - p2, b - p2);
  return side_a * side_b <= 0.0;
}

namespace {

// keep[k] = 0 for the pairs k of `list` that cross a partition at `positions`.
void partition_crossings(const NeighbourList& list, const std::vector<Eigen::Vector3d>& positions,
                         const std::vector<PartitionSegment>& partitions,
                         const PeriodicBoundary& periodic, const std::vector<ParticleKind>* kinds,
                         std::vector<char>& keep) {
  const int n = static_cast<int>(list.offset.size()) - 1;
  // Segments near each particle: boxes of the segments grown by the list radius.
  std::vector<Eigen::AlignedBox2d> boxes;
  for (const auto& s : partitions) {
    Eigen::AlignedBox2d box(s.a);
    box.extend(s.b);
    box.min().array() -= list.radius;
    box.max().array() += list.radius;
    boxes.push_back(box);
  }
  keep.assign(list.index.size(), 1);
#pragma omp parallel for schedule(dynamic, 256) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d xi = positions[i].head<2>();
    for (std::size_t s = 0; s < partitions.size(); ++s) {
      if (!boxes[s].contains(xi)) continue;
      const bool i_fluid = !kinds || (*kinds)[i] == ParticleKind::fluid;
      if (partitions[s].keep_walls && !i_fluid) continue;
      for (int k = list.begin(i); k < list.end(i); ++k) {
        if (partitions[s].keep_walls && kinds && (*kinds)[list.index[k]] != ParticleKind::fluid) {
          continue;
        }
        const Eigen::Vector3d xj =
            positions[i] + periodic.wrap(positions[list.index[k]] - positions[i]);
        if (crosses_partition(positions[i], xj, partitions[s])) keep[k] = 0;
      }
    }
  }
}

}  // namespace

void mask_partition_crossings(NeighbourList& list, const std::vector<Eigen::Vector3d>& positions,
                              const std::vector<PartitionSegment>& partitions,
                              const PeriodicBoundary& periodic,
                              const std::vector<ParticleKind>* kinds) {
  if (partitions.empty()) return;
  std::vector<char> keep;
  partition_crossings(list, positions, partitions, periodic, kinds, keep);
  for (std::size_t k = 0; k < keep.size(); ++k) {
    if (!keep[k]) list.distance[k] = std::numeric_limits<double>::infinity();
  }
}

void remove_partition_crossings(NeighbourList& list, const std::vector<Eigen::Vector3d>& positions,
                                const std::vector<PartitionSegment>& partitions,
                                const PeriodicBoundary& periodic,
                                const std::vector<ParticleKind>* kinds) {
  if (partitions.empty()) return;
  const int n = static_cast<int>(list.offset.size()) - 1;
  std::vector<char> keep;
  partition_crossings(list, positions, partitions, periodic, kinds, keep);
  // Compaction in order (serial): deterministic.
  std::int64_t write = 0;
  std::int64_t begin = 0;
  for (int i = 0; i < n; ++i) {
    const std::int64_t end = list.offset[i + 1];
    for (std::int64_t k = begin; k < end; ++k) {
      if (!keep[k]) continue;
      list.index[write] = list.index[k];
      list.distance[write] = list.distance[k];
      ++write;
    }
    begin = end;
    list.offset[i + 1] = write;
  }
  list.index.resize(write);
  list.distance.resize(write);
}

OpenBoundaries::OpenBoundaries(FluidSystem& system, OpenBoundarySettings settings)
    : system_(system), settings_(settings), state_{settings.velocity,   0.0, system.time(), 0, 0,
                                                   settings.inflow_rows} {
  const OpenBoundarySettings& s = settings_;
  const int dimension = system.parameters().dimension;
  const double l0 = system.parameters().particle_spacing;
  up_ = dimension - 1;
  if (dimension == 3) {
    if (!(s.width > 0.0)) throw std::invalid_argument("OpenBoundaries: 3D needs width > 0");
    across_ = std::max(1, static_cast<int>(std::lround(s.width / l0)));
  }
  if (s.block_rows < 1 || s.inflow_rows < 1 || s.inflow_rows > s.block_rows) {
    throw std::invalid_argument("OpenBoundaries: need 1 <= inflow_rows <= block_rows");
  }
  if (s.level_window <= 0.0) settings_.level_window = 8.0 * l0;
  if (s.level_offset < 0.0) settings_.level_offset = 2.0 * l0;
  if (s.control == OpenBoundarySettings::Control::discharge) {
    if (!(s.discharge > 0.0)) throw std::invalid_argument("OpenBoundaries: discharge must be > 0");
    state_.velocity = s.discharge / (state_.rows * l0);
  }
  if (s.control == OpenBoundarySettings::Control::level) {
    if (!(s.target_level > 0.0)) throw std::invalid_argument("OpenBoundaries: target_level > 0");
    state_.rows = std::clamp(static_cast<int>(std::lround(s.target_level / l0)), 1, s.block_rows);
  }
  for (int i = 0; i < system.particle_count(); ++i) {
    const Eigen::Vector3d& x = system.positions()[i];
    const bool inside = dimension == 2 || (x.y() > 0.0 && x.y() < s.width);
    if (system.kinds()[i] == ParticleKind::wall && x.x() < s.inflow_x && height(x) > s.bed_height &&
        inside) {
      block_.push_back(i);
    }
  }
  if (block_.empty()) throw std::invalid_argument("OpenBoundaries: no moving wall block found");
  set_block_velocity();
}

void OpenBoundaries::restore(const OpenBoundaryState& state) {
  state_ = state;
  set_block_velocity();
}

double OpenBoundaries::wall_speed() const {
  const double ramp = settings_.ramp_time;
  if (!(ramp > 0.0)) return state_.velocity;
  // Scene time, so a restarted run does not ramp again.
  return state_.velocity * std::clamp(system_.time() / ramp, 0.0, 1.0);
}

void OpenBoundaries::set_block_velocity() {
  const double speed = wall_speed();
  for (int i : block_) system_.set_velocity(i, Eigen::Vector3d(speed, 0.0, 0.0));
}

int OpenBoundaries::take_from_pool() {
  const auto& kinds = system_.kinds();
  const int n = system_.particle_count();
  for (int k = 0; k < n; ++k) {
    const int i = (pool_cursor_ + k) % n;
    if (kinds[i] == ParticleKind::inactive) {
      pool_cursor_ = (i + 1) % n;
      return i;
    }
  }
  throw std::runtime_error("OpenBoundaries: particle pool empty (add pool particles to the scene)");
}

int OpenBoundaries::pool_size() const {
  return static_cast<int>(
      std::count(system_.kinds().begin(), system_.kinds().end(), ParticleKind::inactive));
}

double OpenBoundaries::volume_of(double particles) const {
  // Left to right, as the 2D code always formed it (the same bits in 2D).
  const double l0 = system_.parameters().particle_spacing;
  return up_ == 2 ? particles * l0 * l0 * l0 : particles * l0 * l0;
}

double OpenBoundaries::inflow_volume() const {
  return volume_of(static_cast<double>(state_.dissolved_total));
}

int remove_fluid_beyond(FluidSystem& system, double outlet_x) {
  int removed = 0;
  for (int i = 0; i < system.particle_count(); ++i) {
    if (system.kinds()[i] != ParticleKind::fluid) continue;
    const Eigen::Vector3d x = system.positions()[i];
    if (x.x() <= outlet_x) continue;
    system.set_particle(i, ParticleKind::inactive, x, Eigen::Vector3d::Zero());
    ++removed;
  }
  return removed;
}

BoundaryUpdate OpenBoundaries::update() {
  const OpenBoundarySettings& s = settings_;
  const double l0 = system_.parameters().particle_spacing;
  BoundaryUpdate result;
  // Free outflow: particles beyond the outflow line go to the pool.
  for (int i = 0; i < system_.particle_count(); ++i) {
    if (system_.kinds()[i] != ParticleKind::fluid) continue;
    const Eigen::Vector3d x = system_.positions()[i];
    if (x.x() > s.outflow_x || height(x) < s.outflow_min_height) {
      system_.set_particle(i, ParticleKind::inactive, x, Eigen::Vector3d::Zero());
      ++result.recycled;
    }
  }
  state_.recycled_total += result.recycled;
  pool_cursor_ = 0;  // reuse the lowest free slots first

  // Soluble moving wall: columns whose particles passed the inflow line dissolve.
  std::vector<int> passed, kept;
  for (int i : block_) {
    (system_.positions()[i].x() >= s.inflow_x ? passed : kept).push_back(i);
  }
  if (passed.empty()) {
    if (s.ramp_time > 0.0) set_block_velocity();
    return result;
  }
  // Level just downstream of the inflow line (seed 001 section 2.2(3)), measured before the new
  // fluid is released.
  const double x0 = s.inflow_x + s.level_offset, x1 = x0 + s.level_window;
  double top = -std::numeric_limits<double>::infinity();
  int inside = 0;
  for (int i = 0; i < system_.particle_count(); ++i) {
    if (system_.kinds()[i] != ParticleKind::fluid) continue;
    const Eigen::Vector3d& x = system_.positions()[i];
    if (x.x() < x0 || x.x() >= x1 || height(x) < s.bed_height) continue;
    top = std::max(top, height(x));
    ++inside;
  }
  // Mean depth: the water's volume in the window over its bed area (area over length in 2D).
  const double bed_area = up_ == 2 ? s.level_window * s.width : s.level_window;
  const double mean_depth = volume_of(inside) / bed_area;
  if (s.level_measure == OpenBoundarySettings::LevelMeasure::highest) {
    state_.level = std::isfinite(top) ? top + 0.5 * l0 - s.bed_height : 0.0;
  } else {
    state_.level = mean_depth;
  }
  // Water above the block would pour back over it: the inflow cannot hold that level. The mean
  // depth is used whatever the control measures, so a single splash does not count.
  if (mean_depth > s.block_rows * l0) {
    throw std::runtime_error("soluble moving wall: the water level " + std::to_string(mean_depth) +
                             " m at the inflow is above the block height " +
                             std::to_string(s.block_rows * l0) +
                             " m at t = " + std::to_string(system_.time()) +
                             " s; raise the block height or lower the inflow");
  }
  const double now = system_.time();
  switch (s.control) {
    case OpenBoundarySettings::Control::velocity:
      break;
    case OpenBoundarySettings::Control::discharge:
      state_.rows = std::clamp(static_cast<int>(std::lround(state_.level / l0)), 1, s.block_rows);
      state_.velocity = s.discharge / (state_.rows * l0);
      break;
    case OpenBoundarySettings::Control::level:
      state_.velocity +=
          s.level_gain * (s.target_level - state_.level) * (now - state_.last_dissolution_time);
      state_.velocity = std::clamp(state_.velocity, s.min_velocity, s.max_velocity);
      break;
  }
  state_.last_dissolution_time = now;
  // Dissolve: the rows below the control's count become fluid, the others return to the pool.
  // Dissolution uses the velocity the column travelled with, so the released volume is exactly
  // that many rows of l0 x l0 cells.
  double column_x = std::numeric_limits<double>::infinity();
  for (int i : kept) column_x = std::min(column_x, system_.positions()[i].x());
  std::vector<double> passed_x;
  for (int i : passed) passed_x.push_back(system_.positions()[i].x());
  std::sort(passed_x.begin(), passed_x.end());
  int columns = 1;
  for (std::size_t k = 1; k < passed_x.size(); ++k) {
    if (passed_x[k] - passed_x[k - 1] > 0.5 * l0) ++columns;
  }
  for (int i : passed) {
    const Eigen::Vector3d x = system_.positions()[i];
    const Eigen::Vector3d u = system_.velocities()[i];
    const int row = static_cast<int>(std::floor((height(x) - s.bed_height) / l0));
    if (row < state_.rows) {
      system_.set_particle(i, ParticleKind::fluid, x, u);
      ++result.dissolved;
    } else {
      system_.set_particle(i, ParticleKind::inactive, x, Eigen::Vector3d::Zero());
    }
  }
  state_.dissolved_total += result.dissolved;
  // New columns behind the block, one per dissolved column, l0 apart.
  if (!std::isfinite(column_x)) column_x = passed_x.front();
  block_ = kept;
  for (int c = 1; c <= columns; ++c) add_column(column_x - c * l0, result);
  set_block_velocity();
  return result;
}

void OpenBoundaries::add_column(double x, BoundaryUpdate& result) {
  const double l0 = system_.parameters().particle_spacing;
  for (int row = 0; row < settings_.block_rows; ++row) {
    for (int k = 0; k < across_; ++k) {
      Eigen::Vector3d position(x, 0.0, 0.0);
      position[up_] = settings_.bed_height + (row + 0.5) * l0;
      if (up_ == 2) position.y() = (k + 0.5) * settings_.width / across_;
      const int i = take_from_pool();
      system_.set_particle(i, ParticleKind::wall, position,
                           Eigen::Vector3d(wall_speed(), 0.0, 0.0));
      block_.push_back(i);
      ++result.created;
    }
  }
}

}  // namespace cosim::mps
