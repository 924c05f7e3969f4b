#include "cosim/fluid_mps/pool_state.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

namespace cosim::mps {
namespace {

bool boundary(ParticleKind kind) {
  return kind == ParticleKind::wall || kind == ParticleKind::dummy;
}

using Cell = std::pair<int, int>;

// The lattice cell of a position (particles sit at cell centres, (i + 1/2) l0).
Cell cell_of(const Eigen::Vector2d& x, double l0) {
  return {static_cast<int>(std::floor(x.x() / l0)), static_cast<int>(std::floor(x.y() / l0))};
}

// Boundary cells of a set of particles (positions already in the periodic pool's frame) with
// x in [0, length), and their kinds.
template <class Positions, class Kinds>
std::map<Cell, ParticleKind> boundary_cells(const Positions& positions, const Kinds& kinds,
                                            const Eigen::Vector2d& shift, double length,
                                            double l0) {
  std::map<Cell, ParticleKind> cells;
  for (std::size_t i = 0; i < positions.size(); ++i) {
    if (!boundary(kinds[i])) continue;
    const Eigen::Vector2d x = positions[i].template head<2>() + shift;
    if (x.x() < 0.0 || x.x() >= length) continue;
    cells.emplace(cell_of(x, l0), kinds[i]);
  }
  return cells;
}

// Cells of `a` that `b` lacks or holds with another kind; the first of them in `first`.
int unmatched(const std::map<Cell, ParticleKind>& a, const std::map<Cell, ParticleKind>& b,
              Cell& first) {
  int count = 0;
  for (const auto& [cell, kind] : a) {
    const auto found = b.find(cell);
    if (found != b.end() && found->second == kind) continue;
    if (count++ == 0) first = cell;
  }
  return count;
}

void check_geometry(const ParticleSet& scene, const MpsState& frame, const ChainPool& pool,
                    double l0) {
  const double length = pool.x_max - pool.x_min;
  const auto own =
      boundary_cells(scene.positions, scene.kinds, Eigen::Vector2d::Zero(), length, l0);
  // Only the chain's particles inside the reach are shifted into [0, L).
  std::vector<Eigen::Vector3d> positions;
  std::vector<ParticleKind> kinds;
  for (std::size_t i = 0; i < frame.positions.size(); ++i) {
    const double x = frame.positions[i].x();
    if (x < pool.x_min || x >= pool.x_max) continue;
    positions.push_back(frame.positions[i]);
    kinds.push_back(frame.kinds[i]);
  }
  const auto chain = boundary_cells(positions, kinds, pool.shift, length, l0);
  Cell first_own{0, 0}, first_chain{0, 0};
  const int missing = unmatched(own, chain, first_own);
  const int extra = unmatched(chain, own, first_chain);
  if (missing == 0 && extra == 0) return;
  const Cell first = missing > 0 ? first_own : first_chain;
  throw ChainStateError(
      "pool",
      fmt::format("the chain's walls and dummies in pool {} (x from {:.4g} to {:.4g} m), "
                  "shifted by ({:.4g}, {:.4g}) m, are not this scene's: {} of its {} boundary "
                  "cells have no match in the frame and {} of the frame's {} none here (first at "
                  "x = {:.4g}, z = {:.4g} m of the periodic pool); pool_length, step_height, "
                  "weir_height, orifice_height, partition_columns, wall_layers or dummy_layers "
                  "differ from the chain's",
                  pool.pool, pool.x_min, pool.x_max, pool.shift.x(), pool.shift.y(), missing,
                  own.size(), extra, chain.size(), (first.first + 0.5) * l0,
                  (first.second + 0.5) * l0));
}

// "2, 3": the pools of reach `length` (counted from 1 at x = 0) the frame holds fluid in.
std::string pools_with_fluid(const MpsState& frame, double length) {
  std::vector<int> pools;
  for (std::size_t i = 0; i < frame.positions.size(); ++i) {
    if (frame.kinds[i] != ParticleKind::fluid) continue;
    const int k = static_cast<int>(std::floor(frame.positions[i].x() / length)) + 1;
    if (std::find(pools.begin(), pools.end(), k) == pools.end()) pools.push_back(k);
  }
  std::sort(pools.begin(), pools.end());
  std::string names;
  for (const int k : pools) names += (names.empty() ? "" : ", ") + std::to_string(k);
  return names.empty() ? "none" : names;
}

}  // namespace

ChainPool chain_pool(double particle_spacing, const FishwayGeometry& geometry, int pool) {
  // The same cell counts as pool_fishway and periodic_pool (fishway.cpp rounds to whole l0).
  const double l0 = particle_spacing;
  const double length = std::lround(geometry.pool_length / l0) * l0;
  const double step = std::lround(geometry.step_height / l0) * l0;
  ChainPool result;
  result.pool = pool;
  result.x_min = (pool - 1) * length;
  result.x_max = pool * length;
  result.shift = Eigen::Vector2d(-(pool - 1) * length, (pool - 1) * step);
  return result;
}

double boundary_lattice_spacing(const MpsState& frame, const ChainPool& pool) {
  std::vector<double> columns;
  for (std::size_t i = 0; i < frame.positions.size(); ++i) {
    const double x = frame.positions[i].x();
    if (boundary(frame.kinds[i]) && x >= pool.x_min && x < pool.x_max) columns.push_back(x);
  }
  std::sort(columns.begin(), columns.end());
  double spacing = 0.0;
  for (std::size_t i = 1; i < columns.size(); ++i) {
    const double gap = columns[i] - columns[i - 1];
    // Particles of one column share x up to rounding; distinct columns are at least l0 apart.
    if (gap > 1e-9 * std::max(1.0, std::abs(columns[i])) && (spacing == 0.0 || gap < spacing)) {
      spacing = gap;
    }
  }
  return spacing;
}

MpsState extract_chain_pool(const MpsState& frame, const ChainPool& pool) {
  MpsState out;
  out.time = frame.time;
  out.step = frame.step;
  for (std::size_t i = 0; i < frame.positions.size(); ++i) {
    const double x = frame.positions[i].x();
    if (frame.kinds[i] == ParticleKind::inactive || x < pool.x_min || x >= pool.x_max) continue;
    out.positions.push_back(frame.positions[i]);
    out.velocities.push_back(frame.velocities[i]);
    out.pressures.push_back(frame.pressures[i]);
    out.kinds.push_back(frame.kinds[i]);
  }
  return out;
}

MpsState periodic_pool_state(const ParticleSet& periodic_scene, const MpsState& frame,
                             const ChainPool& pool, double particle_spacing) {
  const double l0 = particle_spacing;
  MpsState state;
  const Eigen::Vector3d shift(pool.shift.x(), pool.shift.y(), 0.0);
  for (std::size_t i = 0; i < frame.positions.size(); ++i) {
    const double x = frame.positions[i].x();
    if (frame.kinds[i] != ParticleKind::fluid || x < pool.x_min || x >= pool.x_max) continue;
    state.positions.push_back(frame.positions[i] + shift);
    state.velocities.push_back(frame.velocities[i]);
    state.pressures.push_back(frame.pressures[i]);
    state.kinds.push_back(ParticleKind::fluid);
  }
  if (state.positions.empty()) {
    throw ChainStateError(
        "pool", fmt::format("the frame holds no fluid in pool {} (x from {:.4g} to {:.4g} m); "
                            "its fluid lies in pools {}",
                            pool.pool, pool.x_min, pool.x_max,
                            pools_with_fluid(frame, pool.x_max - pool.x_min)));
  }
  const double spacing = boundary_lattice_spacing(frame, pool);
  if (spacing == 0.0) {
    throw ChainStateError("pool", fmt::format("the frame holds no walls in pool {} (x from {:.4g} "
                                              "to {:.4g} m)",
                                              pool.pool, pool.x_min, pool.x_max));
  }
  if (std::abs(spacing - l0) > 1e-6 * l0) {
    throw ChainStateError(
        "file", fmt::format("the frame's walls in pool {} stand {:.6g} m apart, not "
                            "particle_spacing {:.6g} m: the chain ran at another resolution",
                            pool.pool, spacing, l0));
  }
  check_geometry(periodic_scene, frame, pool, l0);
  for (std::size_t i = 0; i < periodic_scene.size(); ++i) {
    if (periodic_scene.kinds[i] == ParticleKind::fluid) continue;
    state.positions.push_back(periodic_scene.positions[i]);
    state.velocities.push_back(periodic_scene.velocities[i]);
    state.pressures.push_back(0.0);
    state.kinds.push_back(periodic_scene.kinds[i]);
  }
  return state;
}

}  // namespace cosim::mps
