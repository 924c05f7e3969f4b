// The nested keys of the `vegetation_beam` section outside the library's structs (a `plants`
// row, `canopy`, `reference`), each declared once (visit_parameters,
// cosim/scenario/parameters.hpp): vegetation_config.cpp reads them, `cosim keys` lists them.
#pragma once

#include <concepts>
#include <type_traits>

#include "cosim/scenario/parameters.hpp"
#include "vegetation_config.hpp"

namespace cosim::vegetation {

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
