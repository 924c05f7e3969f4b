// The nested keys of the `fluid_mps` section (the section's own keys, `scene` with one struct of
// keys per kind; `scene.inflow`, `scene.chain_state`, `scene.obstacles`, `scene.solids`,
// `restart` and `partitions` are in boundary_keys.hpp, `observe` and `reference` in
// reference_keys.hpp), each declared once (visit_parameters,
// cosim/scenario/parameters.hpp): fluid_config.cpp reads them with their ranges and rules, and
// `cosim keys` lists them. The checks that need another section or a file's contents (a
// reference's scene, a restart's frames, whole cells of a 3D tank) stay in fluid_config.cpp.
//
// A scene kind: a keys struct over the SceneSettings fields its builder reads (they stay flat,
// as main.cpp and scene_3d.cpp build from them), a row in kSceneKinds and a case in
// visit_scene_kind. Its keys are refused for every other kind as "only used with kind: ...".
#pragma once

#include <cmath>
#include <concepts>
#include <type_traits>

#include "cosim/fluid_mps/boundaries.hpp"
#include "cosim/scenario/parameters.hpp"
#include "cosim/scenario/stl_section.hpp"
#include "fluid_config.hpp"

namespace cosim::mps {

// span, the radii of the exchange with solids and output_interval, beside MpsParameters.
struct FluidSectionKeys {
  FluidConfig& config;
};

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, FluidSectionKeys>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  FluidConfig& c = p.config;
  v(Key("span")
        .unit("m")
        .in(Range::positive())
        .doc("2D: the width along y the slice stands for (forces per width times span)"),
    c.span);
  // fluid_config.cpp sets the defaults that depend on l0 and the top level first.
  v(Key("sample_radius")
        .unit("m")
        .in(Range::positive())
        .shown_default("2 particle_spacing")
        .doc("ensemble-average radius around solid nodes (seed 000 r_ev)"),
    c.sample_radius);
  v(Key("displacement_radius")
        .unit("m")
        .in(Range::non_negative())
        .doc("> 0: the fluid leaves the solids' submerged volumes to them, spread this far (at "
             "least the largest element); 0: none"),
    c.displacement_radius);
  v(Key("displacement_ramp")
        .unit("s")
        .in(Range::non_negative())
        .doc("the displaced volumes grow from zero over this long (else the water is blasted away "
             "in one step)"),
    c.displacement_ramp);
  v(Key("output_interval")
        .unit("s")
        .in(Range::positive())
        .shown_default("the top level's output_interval")
        .doc("between particle frames"),
    c.output_interval);
}

enum class SceneKind {
  dam_break,
  still_water_tank,
  periodic_channel,
  open_channel,
  pool_fishway,
  periodic_pool,
  flume
};
inline constexpr scenario::Choices<SceneKind, 7> kSceneKinds{
    {{"dam_break", SceneKind::dam_break},
     {"still_water_tank", SceneKind::still_water_tank},
     {"periodic_channel", SceneKind::periodic_channel},
     {"open_channel", SceneKind::open_channel},
     {"pool_fishway", SceneKind::pool_fishway},
     {"periodic_pool", SceneKind::periodic_pool},
     {"flume", SceneKind::flume}}};

// The keys every scene has: its kind, the walls, and in 3D the tank's width across.
struct SceneKeys {
  SceneSettings& scene;
  SceneKind kind = SceneKind::dam_break;
};

// The water column of Martin & Moyce (1952) released in a closed tank.
struct DamBreakKeys {
  SceneSettings& scene;
  static constexpr bool builds_3d = true, has_inflow = false;
};
struct StillWaterTankKeys {
  SceneSettings& scene;
  static constexpr bool builds_3d = true, has_inflow = false;
};
// A channel periodic along x, driven by the gravity tilt and a pressure drop (seed 000 3.1); in
// 3D between side walls tank_width apart and tank_height high (boundaries.hpp, Channel3d).
struct PeriodicChannelKeys {
  SceneSettings& scene;
  static constexpr bool builds_3d = true, has_inflow = false;
};
// A channel fed by seed 001's soluble moving wall, with a free outfall; in 3D as the periodic
// channel, the block across the whole width.
struct OpenChannelKeys {
  SceneSettings& scene;
  static constexpr bool builds_3d = true, has_inflow = true;
};

// The side walls of a 3D channel (periodic_channel, open_channel): tank_width (SceneKeys) apart,
// this high above the bed.
template <class V>
void visit_channel_walls_3d(SceneSettings& s, V& v) {
  using scenario::Key;
  using scenario::Range;
  v(Key("tank_height")
        .unit("m")
        .in(Range::positive())
        .needed()
        .only_with(s.dimension == 3, "dimension: 3")
        .doc("of the side walls above the bed"),
    s.tank_height);
}
// Seed 001's stepped pool-and-weir fishway, fed by the moving wall.
struct PoolFishwayKeys {
  SceneSettings& scene;
  static constexpr bool builds_3d = false, has_inflow = true;
};
// One pool of the fishway, periodic with a step drop (seed 001 Run-OC).
struct PeriodicPoolKeys {
  SceneSettings& scene;
  static constexpr bool builds_3d = false, has_inflow = false;
};

// A straight 3D channel for a debris flow (seed 004): bed z = 0 over x in [0, length], side
// walls at y = 0 and y = width, end walls at x = 0 and x = length, all wall_height high (the
// debris_dem flume's keys, so one YAML anchor gives both), and a reservoir `water` across the
// whole width, at rest until t = 0. The slope is the world's (world.slope_degrees: x along the
// bed, gravity tilted, docs/architecture.md), so the bed lies on the lattice, where the DEM's
// triangles are. The sizes must be whole cells of particle_spacing (fluid_config.cpp).
struct FlumeKeys {
  SceneSettings& scene;
  static constexpr bool builds_3d = true, has_inflow = false;
};
// The flume's reservoir: x from x_min to x_max, `depth` deep.
struct FlumeWaterKeys {
  SceneSettings& scene;
  double x_max = 0;
};

// Calls f(keys) with the keys struct of `kind` over `scene`.
template <class F>
void visit_scene_kind(SceneKind kind, SceneSettings& scene, F&& f) {
  switch (kind) {
    case SceneKind::dam_break: {
      DamBreakKeys keys{scene};
      f(keys);
      return;
    }
    case SceneKind::still_water_tank: {
      StillWaterTankKeys keys{scene};
      f(keys);
      return;
    }
    case SceneKind::periodic_channel: {
      PeriodicChannelKeys keys{scene};
      f(keys);
      return;
    }
    case SceneKind::open_channel: {
      OpenChannelKeys keys{scene};
      f(keys);
      return;
    }
    case SceneKind::pool_fishway: {
      PoolFishwayKeys keys{scene};
      f(keys);
      return;
    }
    case SceneKind::periodic_pool: {
      PeriodicPoolKeys keys{scene};
      f(keys);
      return;
    }
    case SceneKind::flume: {
      FlumeKeys keys{scene};
      f(keys);
      return;
    }
  }
}

inline bool builds_3d(SceneKind kind) {
  SceneSettings unused;
  bool result = false;
  visit_scene_kind(kind, unused, [&](const auto& keys) { result = keys.builds_3d; });
  return result;
}
inline bool has_inflow(SceneKind kind) {
  SceneSettings unused;
  bool result = false;
  visit_scene_kind(kind, unused, [&](const auto& keys) { result = keys.has_inflow; });
  return result;
}

// "dam_break, still_water_tank": the kinds for which `test` holds.
template <class Test>
std::string scene_kinds_where(Test test) {
  std::string names;
  for (const auto& c : kSceneKinds) {
    if (test(c.value)) names += (names.empty() ? "" : ", ") + std::string(c.name);
  }
  return names;
}

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, SceneKeys>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  SceneSettings& s = p.scene;
  const bool three_d = s.dimension == 3;
  v(Key("kind").needed().doc("which scene is built; its keys are listed per kind below"), p.kind,
    kSceneKinds);
  const std::string in_3d = scene_kinds_where(builds_3d);
  v.rule("kind", !three_d || builds_3d(p.kind),
         "this kind has no 3D scene (dimension: 3 builds " + in_3d + ")");
  v.rule("kind", three_d || p.kind != SceneKind::flume,
         "'flume' is a 3D scene: it needs dimension: 3 (a 2D sloping channel is open_channel or "
         "periodic_channel)");
  v(Key("tank_width")
        .unit("m")
        .in(Range::positive())
        .needed()
        .only_with(three_d && p.kind != SceneKind::flume, "dimension: 3 (a flume's is width)")
        .doc("the tank across (y), between two side walls"),
    s.tank_width);
  v(Key("wall_layers").in(Range::between(1, 10)).doc("wall particles carrying pressure"),
    s.wall_layers);
  v(Key("dummy_layers").in(Range::between(0, 10)).doc("dummy particles behind the walls"),
    s.dummy_layers);
}

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, DamBreakKeys>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  SceneSettings& s = p.scene;
  v(Key("column_width").unit("m").in(Range::positive()).needed().doc("a: the column along x"),
    s.column_width);
  v(Key("column_height").unit("m").in(Range::positive()).needed().doc("of the water column"),
    s.column_height);
  v(Key("tank_length").unit("m").in(Range::positive()).needed().doc("the tank along x"),
    s.tank_length);
  v.rule("tank_length", s.tank_length >= s.column_width, "shorter than the water column");
  v(Key("tank_height").unit("m").in(Range::positive()).needed().doc("of the tank's walls"),
    s.tank_height);
  // The column may stand anywhere along the tank (SPHERIC test 2: against the far wall).
  v(Key("column_x")
        .unit("m")
        .in(Range::non_negative())
        .only_with(s.dimension == 3, "dimension: 3")
        .doc("the column's upstream face"),
    s.column_x);
  v.rule("column_x", s.column_x + s.column_width <= s.tank_length + 1e-12,
         "the column (column_x + column_width) ends beyond the tank");
}

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, StillWaterTankKeys>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  SceneSettings& s = p.scene;
  v(Key("width").unit("m").in(Range::positive()).needed().doc("the tank along x"), s.width);
  v(Key("depth").unit("m").in(Range::positive()).needed().doc("of the still water"), s.depth);
  v(Key("tank_height").unit("m").in(Range::positive()).needed().doc("of the tank's walls"),
    s.tank_height);
}

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, PeriodicChannelKeys>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  SceneSettings& s = p.scene;
  v(Key("length")
        .unit("m")
        .in(Range::positive())
        .needed()
        .doc("one period along x (the bed slope is the world's gravity tilt)"),
    s.length);
  v(Key("depth").unit("m").in(Range::positive()).needed().doc("of the water"), s.depth);
  v(Key("driving_pressure_drop").unit("Pa").doc("p(x_min) - p(x_max) over one period"),
    s.driving_pressure_drop);
  visit_channel_walls_3d(s, v);
  v.rule("tank_height", s.dimension != 3 || s.tank_height >= s.depth,
         "the side walls must reach the water's depth");
}

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, OpenChannelKeys>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  SceneSettings& s = p.scene;
  v(Key("length").unit("m").in(Range::positive()).needed().doc("of the bed (slope: gravity tilt)"),
    s.length);
  v(Key("initial_depth").unit("m").in(Range::non_negative()).needed().doc("water at the start"),
    s.depth);
  v(Key("block_height")
        .unit("m")
        .in(Range::positive())
        .needed()
        .doc("of the soluble moving wall block, above the backed-up level"),
    s.block_height);
  v(Key("block_columns").in(Range::between(1, 100)).doc("columns of the moving wall block"),
    s.block_columns);
  v(Key("pool_particles")
        .in(Range::between(1, 1e7))
        .doc("recycled particles for the inflow (3D: the water in transit, a column of the block "
             "is block_height x tank_width / particle_spacing^2 of them)"),
    s.pool_particles);
  // Seed 000 section 4's outlet beyond `length` (boundaries.hpp, ChannelOutlet).
  const bool two_d = s.dimension == 2;
  v(Key("outlet_flat_length")
        .unit("m")
        .in(Range::non_negative())
        .only_with(two_d, "dimension: 2 (a 3D channel ends in a free overfall)")
        .doc("a bed level in the world after the sloping reach; 0 with no slope: free overfall"),
    s.outlet.flat_length);
  v(Key("outlet_slope_height")
        .unit("m")
        .in(Range::non_negative())
        .only_with(two_d, "dimension: 2 (a 3D channel ends in a free overfall)")
        .doc("height of the 1:1 adverse slope at the end of the level bed, free overfall at "
             "its crest; 0: none"),
    s.outlet.slope_height);
  visit_channel_walls_3d(s, v);
  v.rule("tank_height", s.dimension != 3 || s.tank_height >= s.block_height,
         "the side walls must reach the top of the moving wall block (block_height)");
}

// The pools of both fishway kinds.
template <class V>
void visit_fishway_pools(FishwayGeometry& g, V& v) {
  using scenario::Key;
  using scenario::Range;
  v(Key("pool_length").unit("m").in(Range::positive()).doc("crest to crest"), g.pool_length);
  v(Key("step_height").unit("m").in(Range::non_negative()).doc("floor drop between pools"),
    g.step_height);
  v(Key("weir_height").unit("m").in(Range::positive()).doc("crest above the pool's floor"),
    g.weir_height);
  v(Key("orifice_height")
        .unit("m")
        .in(Range::non_negative())
        .doc("opening at the foot of every partition (seed 001: 0.02); 0: none"),
    g.orifice_height);
  v.rule("orifice_height", g.orifice_height < g.weir_height, "must be below the crest");
  v(Key("partition_columns").in(Range::between(1, 10)).doc("wall particles across a partition"),
    g.partition_columns);
}

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, PoolFishwayKeys>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  SceneSettings& s = p.scene;
  FishwayGeometry& g = s.fishway;
  visit_fishway_pools(g, v);
  v(Key("pools").in(Range::between(1, 100)).doc("pools in a row"), g.pools);
  v(Key("outlet_length").unit("m").in(Range::positive()).doc("apron after the last weir"),
    g.outlet_length);
  v(Key("block_height")
        .unit("m")
        .in(Range::positive())
        .doc("of the moving wall above the first pool's floor; above the initial water level"),
    g.block_height);
  v(Key("block_columns").in(Range::between(1, 100)).doc("columns of the moving wall block"),
    g.block_columns);
  v(Key("pool_particles").in(Range::between(1, 1e7)).doc("recycled particles for the inflow"),
    g.pool_particles);
  // Read after the inflow (fluid_config.cpp), whose discharge sets the head.
  v(Key("fill_to_weir_head")
        .only_with(s.inflow.control == OpenBoundarySettings::Control::discharge,
                   "inflow.control: discharge")
        .doc("start the pools at the Rehbock weir head of the inflow discharge above the crests"),
    s.fill_to_weir_head);
}

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, FlumeKeys>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  SceneSettings& s = p.scene;
  v(Key("length").unit("m").in(Range::positive()).needed().doc("of the bed, along x"),
    s.tank_length);
  v(Key("width").unit("m").in(Range::positive()).needed().doc("between the side walls (y)"),
    s.tank_width);
  v(Key("wall_height").unit("m").in(Range::positive()).needed().doc("of every wall"),
    s.tank_height);
  // The water running off a flume's end: the end wall behind it is only the lattice's edge, and
  // the surge never slams into it (mps::remove_fluid_beyond).
  v(Key("outlet_x")
        .unit("m")
        .in(Range::positive())
        .shown_default("none")
        .doc("fluid past this x leaves the flow; between the water's x_max and the end"),
    s.outlet_x);
  v.rule("outlet_x", !std::isfinite(s.outlet_x) || s.outlet_x < s.tank_length,
         "must lie between the water's x_max and the flume's end");
}

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, FlumeWaterKeys>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  SceneSettings& s = p.scene;
  v(Key("x_min").unit("m").in(Range::non_negative()).doc("the reservoir's upstream face"),
    s.column_x);
  v(Key("x_max").unit("m").in(Range::positive()).needed().doc("its downstream face"), p.x_max);
  v.rule("x_max", p.x_max > s.column_x, "must exceed x_min");
  v.rule("x_max", p.x_max <= s.tank_length + 1e-12, "the water ends beyond the flume");
  v(Key("depth").unit("m").in(Range::positive()).needed().doc("of the water, normal to the bed"),
    s.column_height);
  v.rule("depth", s.column_height <= s.tank_height, "exceeds the flume's wall_height");
}

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, PeriodicPoolKeys>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  SceneSettings& s = p.scene;
  visit_fishway_pools(s.fishway, v);
  v(Key("fill_discharge")
        .unit("m^2/s")
        .in(Range::positive())
        .needed()
        .doc("filled to the crest plus the Rehbock head of this discharge per width"),
    s.fill_discharge);
}

}  // namespace cosim::mps
