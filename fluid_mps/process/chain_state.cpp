#include "chain_state.hpp"

#include <fmt/format.h>

#include <cmath>

#include "boundary_keys.hpp"
#include "cosim/fluid_mps/pool_state.hpp"
#include "cosim/output/point_series.hpp"
#include "cosim/scenario/parameter_reader.hpp"
#include "scene_keys.hpp"

namespace cosim::mps {
namespace {

// The frame nearest to settings.time.
output::PointFrame frame_at(scenario::Section& section, const ChainStateSettings& s) {
  int frames = 0;
  int nearest = -1;
  try {
    frames = output::count_point_frames(s.file);
    nearest = output::nearest_point_frame(s.file, s.time);
  } catch (const std::exception& error) {
    section.fail("file", error.what());
  }
  if (nearest < 0) section.fail("file", s.file.string() + " holds no frames");
  output::PointFrame frame = output::read_point_frame(s.file, nearest);
  if (std::abs(frame.time - s.time) > s.time_tolerance) {
    section.fail("time",
                 fmt::format("{} has no frame within {:.3g} s of t = {:.6g} s: its {} "
                             "frames run from {:.6g} to {:.6g} s, the nearest is at "
                             "{:.6g} s",
                             s.file.string(), s.time_tolerance, s.time, frames,
                             output::read_point_frame_time(s.file, 0),
                             output::read_point_frame_time(s.file, frames - 1), frame.time));
  }
  return frame;
}

// The frame in the fluid's plane: a 2D run's particles lie in the world's x-z plane (y = 0).
MpsState solver_state(scenario::Section& section, const output::PointFrame& frame,
                      const coupler::SolverFrame& world, const std::string& file) {
  for (const auto& x : frame.positions) {
    if (std::abs(x.y()) > 1e-9) {
      section.fail("file", fmt::format("{}: a particle at world y = {:.4g} m: the frame is of a "
                                       "3D run, this scene is 2D (the x-z plane)",
                                       file, x.y()));
    }
  }
  auto field = [&](const auto& map, const char* name) -> const auto& {
    const auto found = map.find(name);
    if (found == map.end()) {
      section.fail(
          "file", fmt::format("{}: the frame at t = {:.6g} s has no '{}'", file, frame.time, name));
    }
    return found->second;
  };
  MpsState state;
  state.time = frame.time;
  for (const auto& x : frame.positions) state.positions.push_back(world.to_solver(x));
  for (const auto& u : field(frame.vectors, "velocity")) {
    state.velocities.push_back(world.to_solver(u));
  }
  state.pressures = field(frame.scalars, "pressure");
  for (const int kind : field(frame.labels, "kind")) {
    if (kind < 0 || kind > 3) section.fail("file", file + ": a particle kind out of range");
    state.kinds.push_back(static_cast<ParticleKind>(kind));
  }
  return state;
}

}  // namespace

std::optional<MpsState> parse_chain_state(scenario::Section& scene, const FluidConfig& config) {
  auto section = scene.optional_child("chain_state");  // null: the level start
  if (!scene.has("chain_state")) return std::nullopt;
  ChainStateSettings s;
  scenario::read_parameters(section, s);
  const MpsState frame = solver_state(section, frame_at(section, s), config.frame, s.file.string());
  // The periodic scene's walls, as main.cpp builds them (on a copy of the parameters).
  MpsParameters parameters = config.parameters;
  std::vector<Weir> weirs;
  const SceneSettings& scene_settings = config.scene;
  ParticleSet periodic;
  try {
    periodic = periodic_pool(parameters, scene_settings.fishway,
                             periodic_pool_fill(scene_settings, config.parameters.gravity.norm()),
                             weirs, scene_settings.wall_layers, scene_settings.dummy_layers);
  } catch (const std::invalid_argument& error) {
    scene.fail("kind", error.what());
  }
  const double l0 = config.parameters.particle_spacing;
  try {
    return periodic_pool_state(periodic, frame, chain_pool(l0, scene_settings.fishway, s.pool), l0);
  } catch (const ChainStateError& error) {
    section.fail(error.key(),
                 fmt::format("{} (t = {:.6g} s): {}", s.file.string(), frame.time, error.what()));
  }
}

}  // namespace cosim::mps
