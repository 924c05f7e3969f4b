// The nested keys of the `debris_dem` section (flume, bed_roughness, dam, box, packing, gate,
// elements, reference), each declared once (visit_parameters, cosim/scenario/parameters.hpp):
// dem_config.cpp reads them with their ranges and rules, `cosim keys` lists them.
#pragma once

#include <concepts>
#include <type_traits>

#include "cosim/debris_dem/scenes.hpp"
#include "cosim/scenario/parameters.hpp"
#include "dem_config.hpp"

namespace cosim::dem {

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, FlumeSpec>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  v(Key("length").unit("m").in(Range::positive()).needed().doc("bed length, from x = 0"), p.length);
  v(Key("width").unit("m").in(Range::positive()).needed().doc("side walls at y = 0 and width"),
    p.width);
  v(Key("wall_height").unit("m").in(Range::positive()).needed().doc("of the side walls"),
    p.wall_height);
  v(Key("upstream_wall").doc("a wall closes x = 0"), p.upstream_wall);
  v(Key("downstream_wall").doc("a wall closes x = length (the water pools below the dam)"),
    p.downstream_wall);
}

// seed 004 fig. 12: fixed spheres of 7-20 mm embedded in the bed.
template <class P, class V>
requires std::same_as<std::remove_const_t<P>, RoughnessSettings>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  v(Key("x0").unit("m").in(Range::non_negative()).needed().doc("start of the rough reach"), p.x0);
  v(Key("x1").unit("m").in(Range::positive()).needed().doc("end of the rough reach"), p.x1);
  v.rule("x1", p.x1 > p.x0, "must exceed x0");
  v(Key("d_min").unit("m").in(Range::positive()).needed().doc("smallest roughness sphere"),
    p.d_min);
  v(Key("d_max").unit("m").in(Range::positive()).needed().doc("largest roughness sphere"), p.d_max);
  v.rule("d_max", p.d_max >= p.d_min, "must not be below d_min");
  v(Key("seed").in(Range::between(0, 2147483647)).doc("of the random placement"), p.seed);
}

// The grid-type check dam of seed 004 fig. 11, across the whole flume.
template <class P, class V>
requires std::same_as<std::remove_const_t<P>, GridDamSpec>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  v(Key("x").unit("m").in(Range::positive()).needed().doc("column axes, inside the flume"), p.x);
  v(Key("column_diameter").unit("m").in(Range::positive()).doc("seed 004: 18 mm wooden columns"),
    p.column_diameter);
  v(Key("horizontal_gap").unit("m").in(Range::positive()).needed().doc("l_H between columns"),
    p.horizontal_gap);
  v(Key("vertical_gap")
        .unit("m")
        .in(Range::non_negative())
        .scenario_default(0.0)
        .doc("l_V between horizontal beams; 0: no beams"),
    p.vertical_gap);
  // dem_config.cpp sets the flume's wall height as the default before reading.
  v(Key("height")
        .unit("m")
        .in(Range::positive())
        .shown_default("the flume's wall_height")
        .doc("of the columns"),
    p.height);
}

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, BoxSettings>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  v(Key("min").unit("m").needed().doc("lower corner: the floor is at its z"), p.min);
  v(Key("max").unit("m").needed().doc("upper corner; the box is open at the top"), p.max);
  v.rule("max", (p.max - p.min).minCoeff() > 0, "must exceed min in x, y and z");
}

// The random packing of seed 004 section 4.1(2); `spheres` is a list of SphereClass.
template <class P, class V>
requires std::same_as<std::remove_const_t<P>, PackingSpec>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  v(Key("box_min").unit("m").needed().doc("lower corner of the packing box"), p.box_min);
  v(Key("box_max").unit("m").needed().doc("upper corner of the packing box"), p.box_max);
  v.rule("box_max", (p.box_max - p.box_min).minCoeff() > 0, "must exceed box_min in x, y and z");
  v(Key("log_count").in(Range::between(0, 1e6)).doc("logs, placed first, axes horizontal"),
    p.log_count);
  v(Key("log_diameter").unit("m").in(Range::positive()).doc("seed 004: 10 mm"), p.log_diameter);
  v(Key("log_length").unit("m").in(Range::positive()).doc("seed 004: 100 mm"), p.log_length);
  v(Key("seed").in(Range::between(0, 2147483647)).doc("of the random placement"), p.seed);
}

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, SphereClass>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  v(Key("diameter").unit("m").in(Range::positive()).needed().doc("of this class"), p.diameter);
  v(Key("count").in(Range::between(0, 1e7)).needed().doc("spheres of this class"), p.count);
}

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, GateSettings>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  v(Key("x").unit("m").in(Range::positive()).needed().doc("downstream of the packing box"), p.x);
  v(Key("settle_time")
        .unit("s")
        .in(Range::non_negative())
        .doc("free fall behind the gate before the run starts"),
    p.settle_time);
}

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, ElementSettings>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  v(Key("kind").needed().doc("a sphere or a log (flat-ended cylinder)"), p.shape, kElementShapes);
  v(Key("center").unit("m").needed().doc("at the start"), p.center);
  v(Key("diameter").unit("m").in(Range::positive()).needed().doc("of the sphere or log"),
    p.diameter);
  const bool log = p.shape == ElementShape::log;
  v(Key("length")
        .unit("m")
        .in(Range::positive())
        .needed()
        .only_with(log, "kind: log")
        .doc("of the log"),
    p.length);
  v(Key("axis").needed().only_with(log, "kind: log").doc("of the log; any length but zero"),
    p.axis);
  v.rule("axis", !log || p.axis.norm() > 0.0, "must not be the zero vector");
  v(Key("density")
        .unit("kg/m^3")
        .in(Range::positive())
        .needed()
        .doc("its own; contact constants from materials.debris or materials.logs"),
    p.density);
  v(Key("velocity").unit("m/s").doc("at the start"), p.velocity);
}

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, ElementReferenceSettings>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  v(Key("kind").needed().doc(
        "settling: Schiller-Naumann terminal velocity; floating: Archimedes draft; hindered: "
        "Richardson-Zaki"),
    p.kind, kElementReferenceKinds);
  v(Key("average_from").unit("s").in(Range::non_negative()).doc("time averages start here"),
    p.average_from);
}

}  // namespace cosim::dem
