#include "fluid_config.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "cosim/output/point_series.hpp"
#include "cosim/scenario/parameter_reader.hpp"
#include "references.hpp"
#include "scene_3d.hpp"

namespace cosim::mps {

using scenario::Range;

namespace {

MpsParameters parse_parameters(scenario::Section& section) {
  MpsParameters p;
  scenario::read_parameters(section, p);  // the keys declared in parameters.hpp
  return p;
}

OpenBoundarySettings parse_inflow(scenario::Section inflow) {
  OpenBoundarySettings settings;
  const std::string control =
      inflow.text("control", "discharge", {"velocity", "discharge", "level"});
  using Control = OpenBoundarySettings::Control;
  settings.control = control == "velocity"    ? Control::velocity
                     : control == "discharge" ? Control::discharge
                                              : Control::level;
  if (settings.control == Control::discharge) {
    settings.discharge = inflow.number("discharge", Range::positive());
  } else if (settings.control == Control::level) {
    settings.target_level = inflow.number("target_level", Range::positive());
    settings.level_gain = inflow.number("level_gain", settings.level_gain, Range::positive());
  }
  settings.velocity = inflow.number("velocity", settings.velocity, Range::non_negative());
  settings.inflow_rows =
      inflow.integer("inflow_rows", settings.inflow_rows, Range::between(1, 1000));
  settings.min_velocity =
      inflow.number("min_velocity", settings.min_velocity, Range::non_negative());
  settings.max_velocity = inflow.number("max_velocity", settings.max_velocity, Range::positive());
  settings.ramp_time = inflow.number("ramp_time", settings.ramp_time, Range::non_negative());
  return settings;
}

SceneSettings parse_scene(scenario::Section scene, double gravity, int dimension, double spacing) {
  if (is_flume_scene(scene)) return parse_flume_scene(scene, dimension, spacing);  // scene_3d
  SceneSettings s;
  s.kind = scene.choice("kind", {"dam_break", "still_water_tank", "periodic_channel",
                                 "open_channel", "pool_fishway", "periodic_pool"});
  // 3D: the tanks of scenes_3d.cpp, `tank_width` across (y); the other kinds are 2D only.
  if (dimension == 3) {
    if (s.kind != "dam_break" && s.kind != "still_water_tank") {
      scene.fail("kind", fmt::format("'{}' has no 3D scene (dimension: 3 builds dam_break, "
                                     "still_water_tank or flume)",
                                     s.kind));
    }
    s.tank_width = scene.number("tank_width", Range::positive());
    // Solid boxes in the tank (world [x, y, z] corners [m]), e.g. SPHERIC test 2's box.
    for (auto& box :
         scene.has("obstacles") ? scene.list("obstacles") : std::vector<scenario::Section>{}) {
      const Eigen::Vector3d low = box.vector3("min"), high = box.vector3("max");
      if ((high.array() <= low.array()).any()) box.fail("max", "must exceed min in x, y and z");
      s.obstacles.emplace_back(low, high);
    }
    s.solids = parse_stl_solids(scene);
  }
  if (s.kind == "dam_break") {
    s.column_width = scene.number("column_width", Range::positive());
    s.column_height = scene.number("column_height", Range::positive());
    s.tank_length = scene.number("tank_length", Range::positive());
    if (s.tank_length < s.column_width) scene.fail("tank_length", "shorter than the water column");
    s.tank_height = scene.number("tank_height", Range::positive());
    if (dimension == 3) {
      // The column may stand anywhere along the tank (SPHERIC test 2: against the far wall).
      s.column_x = scene.number("column_x", 0.0, Range::non_negative());
      if (s.column_x + s.column_width > s.tank_length + 1e-12) {
        scene.fail("column_x", "the column (column_x + column_width) ends beyond the tank");
      }
    }
  } else if (s.kind == "still_water_tank") {
    s.width = scene.number("width", Range::positive());
    s.depth = scene.number("depth", Range::positive());
    s.tank_height = scene.number("tank_height", Range::positive());
  } else if (s.kind == "periodic_channel") {
    s.length = scene.number("length", Range::positive());
    s.depth = scene.number("depth", Range::positive());
    s.driving_pressure_drop = scene.number("driving_pressure_drop", 0.0);
  } else if (s.kind == "pool_fishway" || s.kind == "periodic_pool") {
    FishwayGeometry& g = s.fishway;
    g.pool_length = scene.number("pool_length", g.pool_length, Range::positive());
    g.step_height = scene.number("step_height", g.step_height, Range::non_negative());
    g.weir_height = scene.number("weir_height", g.weir_height, Range::positive());
    g.orifice_height = scene.number("orifice_height", g.orifice_height, Range::non_negative());
    if (g.orifice_height >= g.weir_height) scene.fail("orifice_height", "must be below the crest");
    g.partition_columns =
        scene.integer("partition_columns", g.partition_columns, Range::between(1, 10));
    if (s.kind == "pool_fishway") {
      g.pools = scene.integer("pools", g.pools, Range::between(1, 100));
      g.outlet_length = scene.number("outlet_length", g.outlet_length, Range::positive());
      g.block_height = scene.number("block_height", g.block_height, Range::positive());
      g.block_columns = scene.integer("block_columns", g.block_columns, Range::between(1, 100));
      g.pool_particles = scene.integer("pool_particles", g.pool_particles, Range::between(1, 1e7));
      s.inflow = parse_inflow(scene.child("inflow"));
      // Start the pools at the weir head of the inflow discharge (Rehbock) above their crests.
      if (scene.flag("fill_to_weir_head", false)) {
        if (s.inflow.control != OpenBoundarySettings::Control::discharge) {
          scene.fail("fill_to_weir_head", "needs inflow.control: discharge");
        }
        g.initial_head = rehbock_head(s.inflow.discharge, g.weir_height, gravity);
      }
      if (g.block_height <= g.weir_height + g.initial_head) {
        scene.fail("block_height", "must exceed the initial water level");
      }
    } else {
      s.fill_discharge = scene.number("fill_discharge", Range::positive());
    }
  } else {
    s.length = scene.number("length", Range::positive());
    s.depth = scene.number("initial_depth", Range::non_negative());
    s.block_height = scene.number("block_height", Range::positive());
    s.block_columns = scene.integer("block_columns", s.block_columns, Range::between(1, 100));
    s.pool_particles = scene.integer("pool_particles", s.pool_particles, Range::between(1, 1e7));
    s.inflow = parse_inflow(scene.child("inflow"));
    // Outlet beyond `length` (boundaries.hpp, ChannelOutlet): level bed and 1:1 adverse slope.
    s.outlet.flat_length = scene.number("outlet_flat_length", 0.0, Range::non_negative());
    s.outlet.slope_height = scene.number("outlet_slope_height", 0.0, Range::non_negative());
  }
  s.wall_layers = scene.integer("wall_layers", s.wall_layers, Range::between(1, 10));
  s.dummy_layers = scene.integer("dummy_layers", s.dummy_layers, Range::between(0, 10));
  if (dimension == 3) {
    // tank_3d rounds each size to whole cells l0 and refuses a tank of no cell along one.
    const bool dam = s.kind == "dam_break";
    for (const auto& [key, size] :
         {std::pair{dam ? "tank_length" : "width", dam ? s.tank_length : s.width},
          std::pair{"tank_width", s.tank_width}, std::pair{"tank_height", s.tank_height}}) {
      if (std::lround(size / spacing) < 1) {
        scene.fail(
            key, fmt::format("{} m is less than one cell of particle_spacing {} m", size, spacing));
      }
    }
  }
  return s;
}

// Particles of a scene, roughly: its water plus the wall and dummy layers around the tank (for
// the memory estimate; the builders make the exact set).
double estimated_particles(const SceneSettings& s, const MpsParameters& p) {
  const FishwayGeometry& g = s.fishway;
  const double fishway_length = g.pools * g.pool_length + g.outlet_length;
  const double channel = s.length + s.outlet.flat_length + s.outlet.slope_height;
  double length = std::max({s.tank_length, s.width, channel, fishway_length});
  double height = std::max({s.tank_height, s.depth, s.block_height, g.block_height});
  double water = s.column_width * s.column_height + s.width * s.depth + s.length * s.depth;
  if (s.kind == "pool_fishway" || s.kind == "periodic_pool") water = fishway_length * height;
  const double l0 = p.particle_spacing;
  const double layers = (s.wall_layers + s.dummy_layers) * l0;
  if (p.dimension == 3) {
    const double width = std::max(s.tank_width, l0);
    return (water * width + 2.0 * (length * height + length * width + height * width) * layers) /
           (l0 * l0 * l0);
  }
  return (water + (2.0 * height + length) * layers) / (l0 * l0);
}

// The process reads the frame at its start: an unreadable file or a frame it lacks is refused
// here at the key.
RestartSettings parse_restart(scenario::Section& restart) {
  RestartSettings settings{restart.existing_file("file"), restart.integer("frame", -1)};
  int frames = 0;
  try {
    frames = output::count_point_frames(settings.file);
  } catch (const std::exception& error) {
    restart.fail("file", error.what());
  }
  if (settings.frame >= frames || settings.frame < -frames) {
    restart.fail("frame", fmt::format("{} has {} frames (0 to {}, or -1 to -{} from the end)",
                                      settings.file.string(), frames, frames - 1, frames));
  }
  return settings;
}

// Sensors against a measured record (probe_series): the file is read here, so a malformed row
// or a missing column is refused at its key before any process starts.
ProbeSeriesSettings parse_probe_series(scenario::Section& reference, const FluidConfig& config) {
  ProbeSeriesSettings s;
  const auto file = reference.existing_file("file");
  try {
    s.measured = read_measured_table(file);
  } catch (const std::runtime_error& error) {
    reference.fail("file", error.what());
  }
  const double l0 = config.parameters.particle_spacing;
  s.probe_radius = reference.number("probe_radius", 1.5 * l0, Range::positive());
  s.gauge_half_width = reference.number("gauge_half_width", 2.0 * l0, Range::positive());
  s.arrival_fraction = reference.number("arrival_fraction", 0.1, Range{0.0, 1.0, true});
  auto sensors = [&](const char* key, bool gauge) {
    std::vector<ProbeSeriesSettings::Sensor> out;
    for (auto& entry :
         reference.has(key) ? reference.list(key) : std::vector<scenario::Section>{}) {
      ProbeSeriesSettings::Sensor sensor;
      sensor.column = entry.text("column");
      if (s.measured.column(sensor.column) < 0) {
        entry.fail("column", fmt::format("no column '{}' in {}", sensor.column, file.string()));
      }
      // World [x, y, z] of a probe, [x, y] of a gauge (its depth is along z).
      const auto at = entry.numbers("at");
      if (at.size() != (gauge ? 2u : 3u)) {
        entry.fail("at", gauge ? "expected [x, y]" : "expected [x, y, z]");
      }
      sensor.at = config.frame.to_solver(Eigen::Vector3d(at[0], at[1], gauge ? 0.0 : at[2]));
      out.push_back(sensor);
    }
    return out;
  };
  s.pressure_probes = sensors("pressure_probes", false);
  s.depth_gauges = sensors("depth_gauges", true);
  if (s.pressure_probes.empty() && s.depth_gauges.empty()) {
    reference.fail("pressure_probes", "no pressure_probes and no depth_gauges");
  }
  return s;
}

}  // namespace

FluidConfig parse_config(scenario::Section& section, const scenario::Scene& world_scene) {
  const double scene_output_interval = world_scene.output_interval;
  FluidConfig config;
  config.parameters = parse_parameters(section);
  // The world frame (docs/architecture.md): a 2D fluid computes in the world's x-z plane, which
  // the library holds as its (x, y); it stands for a slice `span` wide along y.
  config.span = section.number("span", 1.0, Range::positive());
  config.frame = coupler::SolverFrame(config.parameters.dimension, config.span);
  const Eigen::Vector3d& gravity = world_scene.world.gravity;
  if (config.parameters.dimension == 2 && gravity.y() != 0.0) {
    throw scenario::ScenarioError(fmt::format(
        "{}: key 'world.gravity': a 2D fluid lives in the x-z plane; gravity ({}, {}, {}) has a "
        "y component",
        world_scene.file.string(), gravity.x(), gravity.y(), gravity.z()));
  }
  config.parameters.gravity = config.frame.to_solver(gravity);
  if (section.has("restart")) {
    auto restart = section.child("restart");
    config.restart = parse_restart(restart);
  }
  // The initial scene is still described on restart: it documents the run and sets the tank.
  config.scene = parse_scene(section.child("scene"), config.parameters.gravity.norm(),
                             config.parameters.dimension, config.parameters.particle_spacing);
  config.parameters.periodic.driving_pressure_drop = config.scene.driving_pressure_drop;
  const double particles = estimated_particles(config.scene, config.parameters);
  scenario::MemoryBudget("fluid_mps")
      .add(section, "particle_spacing", particles * estimated_bytes_per_particle(config.parameters),
           fmt::format("{:.3g} particles x {:.3g} B", particles,
                       estimated_bytes_per_particle(config.parameters)));
  for (auto& partition :
       section.has("partitions") ? section.list("partitions") : std::vector<scenario::Section>{}) {
    // World [x, z] of the partition's ends (the fluid's plane).
    const auto a = partition.numbers("from");
    const auto b = partition.numbers("to");
    if (a.size() != 2) partition.fail("from", "expected [x, z]");
    if (b.size() != 2) partition.fail("to", "expected [x, z]");
    config.parameters.partitions.push_back(
        PartitionSegment{{a[0], a[1]}, {b[0], b[1]}, partition.flag("keep_walls", true)});
  }
  if (section.has("observe")) {
    auto observe = section.child("observe");
    ObservationSettings observation;
    const auto flat = observe.numbers("points");
    if (flat.empty() || flat.size() % 3 != 0) {
      observe.fail("points", "expected a flat list of x, y, z triples");
    }
    for (std::size_t i = 0; i < flat.size(); i += 3) {
      observation.points.push_back(
          config.frame.to_solver(Eigen::Vector3d(flat[i], flat[i + 1], flat[i + 2])));
    }
    observation.radius =
        observe.number("radius", 2.0 * config.parameters.particle_spacing, Range::positive());
    observation.average_from = observe.number("average_from", 0.0, Range::non_negative());
    config.observation = observation;
  }
  const double spacing = config.parameters.particle_spacing;
  config.sample_radius = section.number("sample_radius", 2.0 * spacing, Range::positive());
  // > 0: the solids' submerged volumes spread over this radius (FluidSystem::set_solid_volumes),
  // at least the largest element's size so the solid fraction stays below its cap; 0: none.
  config.displacement_radius = section.number("displacement_radius", 0.0, Range::non_negative());
  config.displacement_ramp = section.number("displacement_ramp", 0.1, Range::non_negative());
  config.output_interval =
      section.number("output_interval", scene_output_interval, Range::positive());
  if (section.has("reference")) {
    auto reference = section.child("reference");
    ReferenceSettings r;
    r.kind = reference.choice(
        "kind", {"martin_moyce", "hydrostatic", "canopy_balance", "weirs", "probe_series"});
    if (r.kind == "probe_series") {
      r.probes = parse_probe_series(reference, config);
    } else if (r.kind == "weirs") {
      if (config.scene.kind != "pool_fishway" && config.scene.kind != "periodic_pool") {
        reference.fail("kind", "weirs needs a pool_fishway or periodic_pool scene");
      }
      r.average_from = reference.number("average_from", Range::non_negative());
    } else if (r.kind == "canopy_balance") {
      if (!config.observation) reference.fail("kind", "canopy_balance needs `observe` points");
      if (config.scene.kind != "periodic_channel") {
        reference.fail("kind", "canopy_balance needs a periodic_channel scene");
      }
      r.canopy_height = reference.number("canopy_height", Range::positive());
      // Nepf (2012) shear-layer penetration, reported when both are given (references.cpp).
      r.drag_coefficient = reference.number("drag_coefficient", 0.0, Range::non_negative());
      r.frontal_area = reference.number("frontal_area", 0.0, Range::non_negative());
      r.average_from = config.observation->average_from;
    } else if (r.kind == "martin_moyce") {
      r.file = reference.existing_file("file");
      r.column_width = reference.number("column_width", Range::positive());
      // The process reads the curves at its start: a malformed row is refused here at the key.
      try {
        ReferenceTracker(r, 9.81);
      } catch (const std::runtime_error& error) {
        reference.fail("file", error.what());
      }
    } else {
      r.still_depth = reference.number("still_depth", Range::positive());
      r.probe_x = reference.number("probe_x");
      r.probe_depths = reference.numbers("probe_depths", Range::positive());
      r.average_from = reference.number("average_from", 0.0, Range::non_negative());
      r.probe_radius = reference.number("probe_radius", 1.5 * spacing, Range::positive());
    }
    config.reference = r;
  }
  return config;
}

}  // namespace cosim::mps
