// The keys of the `fluid_mps` scene's boundaries and starts, each declared once
// (visit_parameters, cosim/scenario/parameters.hpp) as scene_keys.hpp declares the scene kinds':
// `scene.inflow` (seed 001's soluble moving wall), `scene.chain_state`, `scene.obstacles`,
// `scene.solids`, `restart` and `partitions`. fluid_config.cpp reads them with their ranges and
// rules, and `cosim keys` lists them.
#pragma once

#include <concepts>
#include <type_traits>

#include "cosim/fluid_mps/boundaries.hpp"
#include "cosim/scenario/parameters.hpp"
#include "cosim/scenario/stl_section.hpp"
#include "fluid_config.hpp"

namespace cosim::mps {

// `scene.chain_state` of a periodic_pool: its water from one pool of a pool_fishway run
// (cosim/fluid_mps/pool_state.hpp; chain_state.cpp checks the frame against the scene).
template <class P, class V>
requires std::same_as<std::remove_const_t<P>, ChainStateSettings>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  v(Key("file").needed().doc(
        "particles.h5 of a pool_fishway run at this particle_spacing, or the pool kept from one "
        "(fishway_pool_state); walls still come from this scene"),
    p.file);
  v(Key("time").unit("s").in(Range::non_negative()).needed().doc("of the frame to start from"),
    p.time);
  v(Key("time_tolerance")
        .unit("s")
        .in(Range::positive())
        .doc("the frame nearest to time must lie this close (frames are written at the first "
             "window end past each output time)"),
    p.time_tolerance);
  v(Key("pool")
        .in(Range::between(1, 100))
        .needed()
        .doc("the chain's pool, counted from 1 at the inflow (seed 001 Run-OC: the most "
             "downstream); its fluid is shifted by (-(pool - 1) pool_length, (pool - 1) "
             "step_height), fluid outside it is left out"),
    p.pool);
}

inline constexpr scenario::Choices<OpenBoundarySettings::Control, 3> kInflowControls{
    {{"velocity", OpenBoundarySettings::Control::velocity},
     {"discharge", OpenBoundarySettings::Control::discharge},
     {"level", OpenBoundarySettings::Control::level}}};

// `scene.inflow`: seed 001's soluble moving wall (boundaries.hpp).
template <class P, class V>
requires std::same_as<std::remove_const_t<P>, OpenBoundarySettings>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  using Control = OpenBoundarySettings::Control;
  v(Key("control").doc(
        "velocity: a fixed wall speed; discharge: seed 001's level adjustment keeping q; level: "
        "a controller keeping target_level"),
    p.control, kInflowControls);
  v(Key("discharge")
        .unit("m^2/s")
        .in(Range::positive())
        .needed()
        .only_with(p.control == Control::discharge, "control: discharge")
        .doc("q per unit width"),
    p.discharge);
  const bool level = p.control == Control::level;
  v(Key("target_level")
        .unit("m")
        .in(Range::positive())
        .needed()
        .only_with(level, "control: level")
        .doc("kept above the bed"),
    p.target_level);
  v(Key("level_gain")
        .unit("1/s^2")
        .in(Range::positive())
        .only_with(level, "control: level")
        .doc("dU/dt per metre of level error"),
    p.level_gain);
  v(Key("velocity")
        .unit("m/s")
        .in(Range::non_negative())
        .doc("of the wall (control: velocity), its start otherwise"),
    p.velocity);
  v(Key("inflow_rows")
        .in(Range::between(1, 1000))
        .doc("rows a column releases (control: velocity), the first column's otherwise"),
    p.inflow_rows);
  v(Key("min_velocity").unit("m/s").in(Range::non_negative()).doc("slowest wall"), p.min_velocity);
  v(Key("max_velocity").unit("m/s").in(Range::positive()).doc("fastest wall"), p.max_velocity);
  v(Key("ramp_time")
        .unit("s")
        .in(Range::non_negative())
        .doc("soft start: the wall speed rises from 0 over this long; 0: none"),
    p.ramp_time);
}

// A `scene.obstacles` entry (3D): a solid box, world corners.
struct ObstacleKeys {
  Eigen::Vector3d min = Eigen::Vector3d::Zero();
  Eigen::Vector3d max = Eigen::Vector3d::Zero();
};

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, ObstacleKeys>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  v(Key("min").unit("m").needed().doc("lower corner, world [x, y, z]"), p.min);
  v(Key("max").unit("m").needed().doc("upper corner"), p.max);
  v.rule("max", (p.max - p.min).minCoeff() > 0, "must exceed min in x, y and z");
}

// A `scene.solids` entry (3D): a closed STL surface (scene_3d.hpp reads and checks it).
// A `solids` entry: scenario::StlEntryKeys (stl_section.hpp), shared with debris_dem's walls.
using StlSolidKeys = scenario::StlEntryKeys;

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, RestartSettings>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  v(Key("file").needed().doc("an output file (particles.h5) of an earlier run"), p.file);
  v(Key("frame").doc("which of its frames; negative: from the end (-1: the last)"), p.frame);
}

// A `partitions` entry: a thin wall no fluid pair sees through (seed 001 2.2(1)).
template <class P, class V>
requires std::same_as<std::remove_const_t<P>, PartitionSegment>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  v(Key("from").unit("m").needed().doc("one end, world [x, z] (the fluid's plane)"), p.a);
  v(Key("to").unit("m").needed().doc("the other end, world [x, z]"), p.b);
  v(Key("keep_walls").doc("cut fluid pairs only: the partition's walls are seen from both sides"),
    p.keep_walls);
}

}  // namespace cosim::mps
