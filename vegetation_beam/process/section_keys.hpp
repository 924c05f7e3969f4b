// The nested keys of the `vegetation_beam` section outside the library's structs (a `plants`
// row, `canopy`, `reference`), each declared once (visit_parameters,
// cosim/scenario/parameters.hpp): vegetation_config.cpp reads them, `cosim keys` lists them.
#pragma once

#include <concepts>
#include <type_traits>

#include "cosim/scenario/parameters.hpp"
#include "vegetation_config.hpp"

namespace cosim::vegetation {

// Largest force (N) and tip speed (m/s) the check keys accept: far beyond any plant of seed 000
// (honami reeds carry about 1 N of drag), and small enough to catch a unit slip.
inline constexpr double kForceLimit = 1e6;
inline constexpr double kSpeedLimit = 100.0;

inline bool bounded(const Eigen::Vector3d& v, double limit) {
  return v.allFinite() && v.norm() <= limit;
}

// A constant force on the node nearest `at` (references/cantilever.md: tip and point loads).
template <class P, class V>
requires std::same_as<std::remove_const_t<P>, PointLoadSettings>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  v(Key("at")
        .in(Range{0.0, 1.0, true})
        .needed()
        .doc("fraction of the length from the base; the load goes to the nearest node"),
    p.at);
  v(Key("force").unit("N").needed().doc("world frame, for the whole run"), p.force);
  v.rule("force", bounded(p.force, kForceLimit),
         "must be finite with a magnitude of at most 1e+06 N");
}

// Released static deflection (tip_force) or a start in the velocity of linear mode `mode`.
template <class P, class V>
requires std::same_as<std::remove_const_t<P>, PluckSettings>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  v(Key("tip_force").unit("N").doc("held in static equilibrium, released at t = 0"), p.tip_force);
  v.rule("tip_force", bounded(p.tip_force, kForceLimit),
         "must be finite with a magnitude of at most 1e+06 N");
  v(Key("tip_velocity").unit("m/s").doc("the tip's start velocity, in the shape of mode `mode`"),
    p.tip_velocity);
  v.rule("tip_velocity", bounded(p.tip_velocity, kSpeedLimit),
         "must be finite with a magnitude of at most 100 m/s");
  const bool deflected = p.tip_force.norm() > 0, moving = p.tip_velocity.norm() > 0;
  v.rule(deflected ? "tip_velocity" : "tip_force", deflected != moving,
         "give one of tip_force (a released deflection) or tip_velocity (a start in the velocity "
         "of linear mode `mode`)");
  // Read only for a velocity pluck, so that the resolved scenario of a tip-force pluck has no
  // mode to trip over when the process reads it again.
  v(Key("mode")
        .in(Range::between(1, 10))
        .only_with(moving, "tip_velocity")
        .doc("1-based, among distinct frequencies"),
    p.mode);
}

// Section-wide checks: a static start and modal output.
template <class P, class V>
requires std::same_as<std::remove_const_t<P>, BeamChecks>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  v(Key("static_solve").doc("start from static equilibrium (still water, fully submerged)"),
    p.static_solve);
  v(Key("modes")
        .in(Range::between(0, 20))
        .doc("linear natural frequencies written per plant (0: none)"),
    p.modes);
}

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, PlantRow>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  v(Key("count").in(Range::between(1, 1000000)).doc("equal plants in this row"), p.count);
  v(Key("spacing").unit("m").doc("from one plant's base to the next"), p.spacing);
  v.rule("spacing", p.count == 1 || p.spacing.norm() > 0.0,
         "a row of several plants needs a non-zero spacing");
}

// Seed 000 section 4: vegetation density change psi (eq. 24), honami amplitude, tip series.
template <class P, class V>
requires std::same_as<std::remove_const_t<P>, CanopySettings>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  // vegetation_config.cpp sets the defaults that depend on the plants and the output first.
  v(Key("psi_radius")
        .unit("m")
        .in(Range::positive())
        .shown_default("7 plant widths")
        .doc("reach of the density psi (seed 000: 7 d_veg)"),
    p.psi_radius);
  v(Key("streamwise").doc("direction the tips are measured along; any length but zero"),
    p.streamwise);
  v.rule("streamwise", p.streamwise.norm() > 0.0, "must not be zero");
  v(Key("amplitude_from").unit("s").in(Range::non_negative()).doc("tip extremes from here on"),
    p.amplitude_from);
  v(Key("tip_interval")
        .unit("s")
        .in(Range::positive())
        .shown_default("output_interval")
        .doc("between rows of tips.csv"),
    p.tip_interval);
}

// The large-deflection elastica of one plant in a uniform stream (elastica.hpp).
template <class P, class V>
requires std::same_as<std::remove_const_t<P>, ElasticaReference>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  v(Key("kind").needed().doc("the steady bent shape in a uniform stream"), p.kind, kReferenceKinds);
  v(Key("plant").in(Range::between(0, 1e9)).doc("which plant, counted over all rows"), p.plant);
  v(Key("velocity").unit("m/s").needed().doc("the uniform stream"), p.velocity);
  v(Key("average_over")
        .unit("s")
        .in(Range::positive())
        .needed()
        .doc("the tip is averaged over this long at the end"),
    p.average_over);
}

}  // namespace cosim::vegetation
