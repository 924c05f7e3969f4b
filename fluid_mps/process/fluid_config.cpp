#include "fluid_config.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include "boundary_keys.hpp"
#include "chain_state.hpp"
#include "cosim/output/point_series.hpp"
#include "cosim/scenario/parameter_reader.hpp"
#include "reference_keys.hpp"
#include "references.hpp"
#include "scene_3d.hpp"
#include "scene_keys.hpp"

namespace cosim::mps {

namespace {

MpsParameters parse_parameters(scenario::Section& section) {
  MpsParameters p;
  scenario::read_parameters(section, p);  // the keys declared in parameters.hpp
  return p;
}

// The keys of every kind's struct (KeyTable rows of the library defaults).
template <class VisitKind, class Kind>
std::vector<std::string> keys_of_kind(VisitKind visit_kind, Kind kind) {
  scenario::KeyTable table;
  visit_kind(kind, table);
  std::vector<std::string> keys;
  for (const auto& row : table.rows()) keys.push_back(row.key);
  return keys;
}

// A key that only other kinds declare is refused as "only used with kind: ..." (clearer than
// "unknown key" for a key written for another scene or reference).
template <class Kind, std::size_t N, class VisitKind>
void refuse_other_kinds(scenario::Section& section, Kind chosen,
                        const scenario::Choices<Kind, N>& kinds, VisitKind visit_kind) {
  const auto own = keys_of_kind(visit_kind, chosen);
  std::map<std::string, std::string> users;  // key -> the kinds that declare it
  for (const auto& c : kinds) {
    for (const auto& key : keys_of_kind(visit_kind, c.value)) {
      std::string& names = users[key];
      names += (names.empty() ? "" : ", ") + std::string(c.name);
    }
  }
  for (const auto& [key, names] : users) {
    if (section.has(key) && std::find(own.begin(), own.end(), key) == own.end()) {
      section.fail(key, "only used with kind: " + names);
    }
  }
}

void describe_scene_kind(SceneKind kind, scenario::KeyTable& table) {
  SceneSettings defaults;
  visit_scene_kind(kind, defaults,
                   [&](const auto& keys) { scenario::describe_parameters(table, keys); });
}

void describe_reference_kind(ReferenceKind kind, scenario::KeyTable& table) {
  ReferenceSettings defaults;
  visit_reference_kind(kind, defaults,
                       [&](const auto& keys) { scenario::describe_parameters(table, keys); });
}

void forbid(scenario::Section& section, const std::string& key, const std::string& needs) {
  if (section.has(key)) section.fail(key, "only used with " + needs);
}

SceneSettings parse_scene(scenario::Section scene, double gravity, int dimension, double spacing) {
  SceneSettings s;
  s.dimension = dimension;
  SceneKeys common{s};
  scenario::read_parameters(scene, common);  // kind, walls, the 3D tank's width
  const SceneKind kind = common.kind;
  s.kind = std::string(scenario::choice_name(kSceneKinds, kind));
  refuse_other_kinds(scene, kind, kSceneKinds, describe_scene_kind);
  if (has_inflow(kind)) {
    auto inflow = scene.child("inflow");
    scenario::read_parameters(inflow, s.inflow);  // before the kind's keys, which depend on it
  } else {
    forbid(scene, "inflow", "kind: " + scene_kinds_where(has_inflow));
  }
  visit_scene_kind(kind, s, [&](auto& keys) { scenario::read_parameters(scene, keys); });
  const bool channel = kind == SceneKind::periodic_channel || kind == SceneKind::open_channel;
  if (dimension == 3 && channel) {
    // The 3D channel builders make the bed and side walls only (boundaries.hpp, Channel3d).
    for (const char* key : {"obstacles", "solids"}) {
      forbid(scene, key, "a 3D tank (kind: dam_break, still_water_tank, flume)");
    }
  } else if (dimension == 3) {
    for (auto& box :
         scene.has("obstacles") ? scene.list("obstacles") : std::vector<scenario::Section>{}) {
      ObstacleKeys corners;
      scenario::read_parameters(box, corners);
      s.obstacles.emplace_back(corners.min, corners.max);
    }
    s.solids = parse_stl_solids(scene);
  } else {
    for (const char* key : {"obstacles", "solids"}) forbid(scene, key, "dimension: 3");
  }
  if (kind == SceneKind::pool_fishway) {
    FishwayGeometry& g = s.fishway;
    // Start the pools at the weir head of the inflow discharge (Rehbock) above their crests.
    if (s.fill_to_weir_head)
      g.initial_head = rehbock_head(s.inflow.discharge, g.weir_height, gravity);
    if (g.block_height <= g.weir_height + g.initial_head) {
      scene.fail("block_height", "must exceed the initial water level");
    }
  }
  if (kind == SceneKind::flume) {
    auto water = scene.child("water");
    FlumeWaterKeys reservoir{s};
    scenario::read_parameters(water, reservoir);
    s.column_width = reservoir.x_max - s.column_x;
    if (std::isfinite(s.outlet_x) && s.outlet_x <= reservoir.x_max) {
      scene.fail("outlet_x", "must lie between the water's x_max and the flume's end");
    }
    // tank_3d rounds each size to whole cells l0; a face off the lattice would move the fluid's
    // wall away from the DEM's by up to l0 / 2, so the sizes must be whole cells (1e-6 relative).
    for (const auto& [key, size] :
         {std::pair{"length", s.tank_length}, std::pair{"width", s.tank_width},
          std::pair{"wall_height", s.tank_height}}) {
      const double cells = size / spacing;
      if (std::lround(cells) < 1 || std::abs(cells - std::round(cells)) > 1e-6 * cells) {
        scene.fail(key, fmt::format("{} m is not a whole number of particle_spacing {} m cells: "
                                    "the fluid's walls would not stand where the debris' do",
                                    size, spacing));
      }
    }
  } else {
    forbid(scene, "water", "kind: flume");
  }
  if (dimension == 3 && kind != SceneKind::flume) {
    // tank_3d rounds each size to whole cells l0 and refuses a tank of no cell along one.
    const bool dam = kind == SceneKind::dam_break;
    const auto along = dam       ? std::pair{"tank_length", s.tank_length}
                       : channel ? std::pair{"length", s.length}
                                 : std::pair{"width", s.width};
    for (const auto& [key, size] :
         {along, std::pair{"tank_width", s.tank_width}, std::pair{"tank_height", s.tank_height}}) {
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
  const double pool = s.kind == "open_channel" ? s.pool_particles : 0.0;  // its inflow's
  if (p.dimension == 3) {
    const double width = std::max(s.tank_width, l0);
    return (water * width + 2.0 * (length * height + length * width + height * width) * layers) /
               (l0 * l0 * l0) +
           pool;
  }
  return (water + (2.0 * height + length) * layers) / (l0 * l0) + pool;
}

// The process reads the frame at its start: an unreadable file or a frame it lacks is refused
// here at the key.
RestartSettings parse_restart(scenario::Section& restart) {
  RestartSettings settings;
  scenario::read_parameters(restart, settings);
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
void parse_probe_series(scenario::Section& reference, const FluidConfig& config,
                        ProbeSeriesSettings& s, const std::filesystem::path& file) {
  try {
    s.measured = read_measured_table(file);
  } catch (const std::runtime_error& error) {
    reference.fail("file", error.what());
  }
  auto column = [&](scenario::Section& entry, const std::string& name) {
    if (s.measured.column(name) < 0) {
      entry.fail("column", fmt::format("no column '{}' in {}", name, file.string()));
    }
  };
  for (auto& entry : reference.has("pressure_probes") ? reference.list("pressure_probes")
                                                      : std::vector<scenario::Section>{}) {
    PressureProbeKeys probe;
    scenario::read_parameters(entry, probe);
    column(entry, probe.column);
    s.pressure_probes.push_back({probe.column, config.frame.to_solver(probe.at)});
  }
  for (auto& entry : reference.has("depth_gauges") ? reference.list("depth_gauges")
                                                   : std::vector<scenario::Section>{}) {
    DepthGaugeKeys gauge;
    scenario::read_parameters(entry, gauge);
    column(entry, gauge.column);
    s.depth_gauges.push_back(
        {gauge.column, config.frame.to_solver(Eigen::Vector3d(gauge.at.x(), gauge.at.y(), 0.0))});
  }
  if (s.pressure_probes.empty() && s.depth_gauges.empty()) {
    reference.fail("pressure_probes", "no pressure_probes and no depth_gauges");
  }
}

ReferenceSettings parse_reference(scenario::Section& reference, const FluidConfig& config) {
  ReferenceSettings r;
  ReferenceKeys common{r};
  scenario::read_parameters(reference, common);
  const ReferenceKind kind = common.kind;
  r.kind = std::string(scenario::choice_name(kReferenceKinds, kind));
  refuse_other_kinds(reference, kind, kReferenceKinds, describe_reference_kind);
  if (kind != ReferenceKind::probe_series) {
    for (const char* key : {"pressure_probes", "depth_gauges"}) {
      forbid(reference, key, "kind: probe_series");
    }
  }
  // The defaults that scale with l0, for the kinds that read them.
  const double l0 = config.parameters.particle_spacing;
  if (kind == ReferenceKind::hydrostatic) r.probe_radius = 1.5 * l0;
  if (kind == ReferenceKind::probe_series) {
    r.probes.probe_radius = 1.5 * l0;
    r.probes.gauge_half_width = 2.0 * l0;
  }
  const std::string& scene = config.scene.kind;
  if (kind == ReferenceKind::weirs && scene != "pool_fishway" && scene != "periodic_pool") {
    reference.fail("kind", "weirs needs a pool_fishway or periodic_pool scene");
  }
  if (kind == ReferenceKind::free_overfall) {
    // Rouse's end depth is that of a free overfall from a horizontal bed at a known discharge.
    const SceneSettings& s = config.scene;
    if (scene != "open_channel")
      reference.fail("kind", "free_overfall needs an open_channel scene");
    if (s.inflow.control != OpenBoundarySettings::Control::discharge) {
      reference.fail("kind",
                     "free_overfall needs the inflow's control: discharge (q is its scale)");
    }
    if (!s.outlet.empty()) {
      reference.fail("kind",
                     "free_overfall needs the bed to end in the overfall (no outlet_ keys)");
    }
    if (std::abs(config.parameters.gravity.x()) > 1e-9 * config.parameters.gravity.norm()) {
      reference.fail("kind", "free_overfall holds for a horizontal bed (world.slope_degrees: 0)");
    }
  }
  if (kind == ReferenceKind::canopy_balance) {
    if (!config.observation) reference.fail("kind", "canopy_balance needs `observe` points");
    if (scene != "periodic_channel") {
      reference.fail("kind", "canopy_balance needs a periodic_channel scene");
    }
  }
  visit_reference_kind(kind, r, [&](auto& keys) { scenario::read_parameters(reference, keys); });
  if (kind == ReferenceKind::probe_series) {
    parse_probe_series(reference, config, r.probes, r.file);
  } else if (kind == ReferenceKind::canopy_balance) {
    r.average_from = config.observation->average_from;
  } else if (kind == ReferenceKind::martin_moyce) {
    // The process reads the curves at its start: a malformed row is refused here at the key.
    try {
      ReferenceTracker(r, 9.81);
    } catch (const std::runtime_error& error) {
      reference.fail("file", error.what());
    }
  }
  return r;
}

}  // namespace

double periodic_pool_fill(const SceneSettings& scene, double gravity) {
  const FishwayGeometry& g = scene.fishway;
  return g.weir_height + rehbock_head(scene.fill_discharge, g.weir_height, gravity);
}

FluidConfig parse_config(scenario::Section& section, const scenario::Scene& world_scene) {
  FluidConfig config;
  config.parameters = parse_parameters(section);
  const double spacing = config.parameters.particle_spacing;
  config.sample_radius = 2.0 * spacing;
  config.output_interval = world_scene.output_interval;
  FluidSectionKeys own{config};
  scenario::read_parameters(section, own);  // span, the exchange radii, output_interval
  // The world frame (docs/architecture.md): a 2D fluid computes in the world's x-z plane, which
  // the library holds as its (x, y); it stands for a slice `span` wide along y.
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
  auto scene = section.child("scene");
  config.scene =
      parse_scene(scene, config.parameters.gravity.norm(), config.parameters.dimension, spacing);
  if (config.scene.kind == "periodic_pool") {
    config.initial_state = parse_chain_state(scene, config);
    if (config.initial_state && config.restart) {
      scene.fail("chain_state", "a restart replaces the initial scene: give one of the two");
    }
  } else {
    forbid(scene, "chain_state", "kind: periodic_pool");
  }
  if (config.parameters.fill_lattice == MpsParameters::FillLattice::fcc) {
    if (config.parameters.dimension != 3) {
      section.fail("fill_lattice", "fcc is a 3D lattice (dimension: 3)");
    }
    const std::string& kind = config.scene.kind;
    if (kind == "flume") {  // its walls must stay on the debris' whole cells l0
      section.fail("fill_lattice", "fcc fits its layers to the water; kind: flume needs cubic");
    }
    if (kind == "periodic_channel" || kind == "open_channel") {
      section.fail("fill_lattice", "the 3D channels are built on the cubic lattice (kind: " + kind +
                                       " needs cubic)");
    }
  }
  config.parameters.periodic.driving_pressure_drop = config.scene.driving_pressure_drop;
  const double particles = estimated_particles(config.scene, config.parameters);
  scenario::MemoryBudget("fluid_mps")
      .add(section, "particle_spacing", particles * estimated_bytes_per_particle(config.parameters),
           fmt::format("{:.3g} particles x {:.3g} B", particles,
                       estimated_bytes_per_particle(config.parameters)));
  for (auto& partition :
       section.has("partitions") ? section.list("partitions") : std::vector<scenario::Section>{}) {
    PartitionSegment segment;
    scenario::read_parameters(partition, segment);
    config.parameters.partitions.push_back(segment);
  }
  if (section.has("observe")) {
    auto observe = section.child("observe");
    ObservationSettings observation;
    observation.radius = 2.0 * spacing;
    ObserveKeys keys{observation, {}};
    scenario::read_parameters(observe, keys);
    for (std::size_t i = 0; i < keys.points.size(); i += 3) {
      observation.points.push_back(config.frame.to_solver(
          Eigen::Vector3d(keys.points[i], keys.points[i + 1], keys.points[i + 2])));
    }
    config.observation = observation;
  }
  if (section.has("reference")) {
    auto reference = section.child("reference");
    config.reference = parse_reference(reference, config);
  }
  return config;
}

}  // namespace cosim::mps
