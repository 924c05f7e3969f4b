// The `fluid_mps` section of a scenario: MPS parameters, the initial scene (or a restart from an
// output frame), coupling to solids, outputs and the reference the run is checked against.
#pragma once

#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "cosim/coupler/frame.hpp"
#include "cosim/fluid_mps/boundaries.hpp"
#include "cosim/fluid_mps/fishway.hpp"
#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/scenes.hpp"
#include "cosim/scenario/scene.hpp"
#include "cosim/scenario/section.hpp"
#include "probe_series.hpp"

namespace cosim::mps {

// The scene's values, flat as the builders read them; scene_keys.hpp declares the keys of each
// kind over them.
struct SceneSettings {
  // dam_break | still_water_tank | periodic_channel | open_channel | pool_fishway | periodic_pool
  // | flume (3D only, scene_3d.hpp: tank_length, tank_width, tank_height and the column)
  std::string kind;
  int dimension = 2;  // of the fluid (not a scene key): the 3D keys depend on it
  double column_width = 0, column_height = 0;  // dam_break
  double column_x = 0;                         // dam_break in 3D: upstream face's x [m]
  double width = 0, depth = 0;                 // still_water_tank, channels (initial depth)
  double tank_length = 0, tank_height = 0;
  // dimension 3 (dam_break, still_water_tank): the tank's width across (y) and solid boxes in
  // the tank [m]
  double tank_width = 0;
  std::vector<Eigen::AlignedBox3d> obstacles;
  std::vector<TriangleMesh> solids;  // dimension 3: closed STL surfaces [m] (scene_3d.hpp)
  double length = 0;                 // channels (the bed slope is the world's gravity tilt)
  double driving_pressure_drop = 0;  // periodic_channel: p(x_min) - p(x_max) [Pa]
  double block_height = 0;           // open_channel: height of the soluble moving wall block
  int block_columns = 4, pool_particles = 400;
  int wall_layers = 2, dummy_layers = 2;
  OpenBoundarySettings inflow;     // open_channel, pool_fishway
  ChannelOutlet outlet;            // open_channel: level bed and adverse slope beyond `length`
  FishwayGeometry fishway;         // pool_fishway, periodic_pool
  bool fill_to_weir_head = false;  // pool_fishway: sets fishway.initial_head from the inflow
  double fill_discharge = 0;       // periodic_pool: fill to the crest plus the weir head of this q
  std::vector<Weir> weirs;         // filled by the fishway scene builders
  // flume: fluid past this x leaves the flow (mps::remove_fluid_beyond; scene_3d.hpp) [m]
  double outlet_x = std::numeric_limits<double>::infinity();
};

// Eulerian observation points (velocity and water presence), recorded every window.
struct ObservationSettings {
  std::vector<Eigen::Vector3d> points;
  double radius = 0;
  double average_from = 0;
};

struct RestartSettings {
  std::filesystem::path file;  // an output file (particles.h5) of an earlier run
  int frame = -1;              // negative: from the end
};

// periodic_pool: start from one pool of a pool_fishway run's output frame (chain_state.hpp).
struct ChainStateSettings {
  std::filesystem::path file;    // particles.h5 of a pool_fishway run, or the pool kept from it
  double time = 0;               // of the frame [s]
  double time_tolerance = 0.01;  // the frame nearest to `time` must lie this close [s]
  int pool = 1;                  // of the chain, counted from 1 at the inflow
};

struct ReferenceSettings {
  std::string kind;  // martin_moyce | hydrostatic | canopy_balance | weirs | probe_series
  std::filesystem::path file;
  double column_width = 0;           // martin_moyce: a
  std::vector<double> probe_depths;  // hydrostatic: below the still surface, at mid tank
  double still_depth = 0;
  double probe_x = 0;
  double average_from = 0;   // hydrostatic, weirs: time averaging starts here
  double probe_radius = 0;   // hydrostatic: particles within this radius are averaged [m]
  double canopy_height = 0;  // canopy_balance: the inflection of u(y) is expected there
  // canopy_balance: C_D and a = n d, the stems' frontal area per volume [1/m], of Nepf's
  // delta_e = 0.23 / (C_D a); zero: not reported.
  double drag_coefficient = 0, frontal_area = 0;
  ProbeSeriesSettings probes;  // probe_series: the sensors and the measured record
};

struct FluidConfig {
  MpsParameters parameters;
  SceneSettings scene;
  std::optional<RestartSettings> restart;
  // periodic_pool with chain_state: the first state (the chain pool's fluid, the scene's walls).
  std::optional<MpsState> initial_state;
  double sample_radius = 0;  // ensemble-average radius around solid nodes (seed 000 r_ev)
  // > 0: the fluid leaves the solids' submerged volumes to them, spread over this radius [m],
  // grown from zero over the first displacement_ramp [s] (water present from the start would
  // otherwise be blasted away in one step).
  double displacement_radius = 0;
  double displacement_ramp = 0.1;
  double span = 1;             // 2D: the width along y the slice stands for [m]
  coupler::SolverFrame frame;  // world <-> the library's coordinates
  double output_interval = 0;
  std::optional<ReferenceSettings> reference;
  std::optional<ObservationSettings> observation;
};

// `scene`: the top level, already read (output interval, the world's gravity).
FluidConfig parse_config(scenario::Section& section, const scenario::Scene& scene);

// periodic_pool: the level the pool is filled to, the crest plus the Rehbock head of
// fill_discharge [m].
double periodic_pool_fill(const SceneSettings& scene, double gravity);

}  // namespace cosim::mps
