// The keys of the `fluid_mps` section's `observe` points and `reference` (one struct per
// reference kind, and its sensors), each declared once (visit_parameters,
// cosim/scenario/parameters.hpp) as scene_keys.hpp declares the scene's: fluid_config.cpp reads
// them with their ranges and rules, and `cosim keys` lists them. The checks that need the scene
// (a reference's kind against the scene's kind) stay in fluid_config.cpp.
#pragma once

#include <concepts>
#include <string>
#include <type_traits>
#include <vector>

#include "cosim/scenario/parameters.hpp"
#include "fluid_config.hpp"

namespace cosim::mps {

// `observe`: Eulerian points recorded every window; the points are given in the world frame and
// turned into the solver's by fluid_config.cpp.
struct ObserveKeys {
  ObservationSettings& observation;
  std::vector<double> points;
};

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, ObserveKeys>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  v(Key("points").unit("m").needed().doc("a flat list of world x, y, z triples"), p.points);
  v.rule("points", !p.points.empty() && p.points.size() % 3 == 0,
         "expected a flat list of x, y, z triples");
  // fluid_config.cpp sets the default from l0 first.
  v(Key("radius")
        .unit("m")
        .in(Range::positive())
        .shown_default("2 particle_spacing")
        .doc("velocity and water presence averaged within it"),
    p.observation.radius);
  v(Key("average_from").unit("s").in(Range::non_negative()).doc("time means start here"),
    p.observation.average_from);
}

enum class ReferenceKind {
  martin_moyce,
  hydrostatic,
  canopy_balance,
  weirs,
  probe_series,
  free_overfall
};
inline constexpr scenario::Choices<ReferenceKind, 6> kReferenceKinds{
    {{"martin_moyce", ReferenceKind::martin_moyce},
     {"hydrostatic", ReferenceKind::hydrostatic},
     {"canopy_balance", ReferenceKind::canopy_balance},
     {"weirs", ReferenceKind::weirs},
     {"probe_series", ReferenceKind::probe_series},
     {"free_overfall", ReferenceKind::free_overfall}}};

struct ReferenceKeys {
  ReferenceSettings& reference;
  ReferenceKind kind = ReferenceKind::martin_moyce;
};
struct MartinMoyceKeys {
  ReferenceSettings& reference;
};
struct HydrostaticKeys {
  ReferenceSettings& reference;
};
struct CanopyBalanceKeys {
  ReferenceSettings& reference;
};
struct WeirsKeys {
  ReferenceSettings& reference;
};
struct ProbeSeriesKeys {
  ReferenceSettings& reference;
};
struct FreeOverfallKeys {
  ReferenceSettings& reference;
};

template <class F>
void visit_reference_kind(ReferenceKind kind, ReferenceSettings& reference, F&& f) {
  switch (kind) {
    case ReferenceKind::martin_moyce: {
      MartinMoyceKeys keys{reference};
      f(keys);
      return;
    }
    case ReferenceKind::hydrostatic: {
      HydrostaticKeys keys{reference};
      f(keys);
      return;
    }
    case ReferenceKind::canopy_balance: {
      CanopyBalanceKeys keys{reference};
      f(keys);
      return;
    }
    case ReferenceKind::weirs: {
      WeirsKeys keys{reference};
      f(keys);
      return;
    }
    case ReferenceKind::probe_series: {
      ProbeSeriesKeys keys{reference};
      f(keys);
      return;
    }
    case ReferenceKind::free_overfall: {
      FreeOverfallKeys keys{reference};
      f(keys);
      return;
    }
  }
}

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, ReferenceKeys>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  v(Key("kind").needed().doc(
        "martin_moyce: surge front and residual column (dam_break); hydrostatic: pressure at "
        "depth; canopy_balance: inflection at the canopy top (periodic_channel with observe); "
        "weirs: Rehbock head at every crest (fishways); probe_series: sensors against a "
        "measured record; free_overfall: Rouse's end depth of a horizontal open_channel"),
    p.kind, kReferenceKinds);
}

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, MartinMoyceKeys>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  v(Key("file").needed().doc("the measured curves (references/martin_moyce_1952.csv)"),
    p.reference.file);
  v(Key("column_width").unit("m").in(Range::positive()).needed().doc("a, the curves' scale"),
    p.reference.column_width);
}

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, HydrostaticKeys>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  ReferenceSettings& r = p.reference;
  v(Key("still_depth").unit("m").in(Range::positive()).needed().doc("of the still surface"),
    r.still_depth);
  v(Key("probe_x").unit("m").needed().doc("world x of the probes (y: mid-tank)"), r.probe_x);
  v(Key("probe_depths").unit("m").in(Range::positive()).needed().doc("below the still surface"),
    r.probe_depths);
  v(Key("average_from").unit("s").in(Range::non_negative()).doc("time means start here"),
    r.average_from);
  // fluid_config.cpp sets the default from l0 first.
  v(Key("probe_radius")
        .unit("m")
        .in(Range::positive())
        .shown_default("1.5 particle_spacing")
        .doc("particles within it are averaged, each pressure carried hydrostatically to the "
             "probe"),
    r.probe_radius);
}

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, CanopyBalanceKeys>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  v(Key("canopy_height")
        .unit("m")
        .in(Range::positive())
        .needed()
        .doc("where u(z) should inflect; time means from observe.average_from"),
    p.reference.canopy_height);
  // Nepf (2012) shear-layer penetration delta_e = 0.23 / (C_D a), reported when both are given.
  v(Key("drag_coefficient")
        .in(Range::non_negative())
        .doc("C_D of the canopy's stems, for Nepf's delta_e; 0: not reported"),
    p.reference.drag_coefficient);
  v(Key("frontal_area")
        .unit("1/m")
        .in(Range::non_negative())
        .doc("a = n d, frontal area per volume, for Nepf's delta_e; 0: not reported"),
    p.reference.frontal_area);
}

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, WeirsKeys>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  v(Key("average_from").unit("s").in(Range::non_negative()).needed().doc("time means start here"),
    p.reference.average_from);
}

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, ProbeSeriesKeys>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  ProbeSeriesSettings& s = p.reference.probes;
  v(Key("file").needed().doc("the measured record: a CSV, '#' comments, a header, time first"),
    p.reference.file);
  // fluid_config.cpp sets the defaults from l0 first.
  v(Key("probe_radius")
        .unit("m")
        .in(Range::positive())
        .shown_default("1.5 particle_spacing")
        .doc("a pressure probe averages fluid and wall particles within it"),
    s.probe_radius);
  v(Key("gauge_half_width")
        .unit("m")
        .in(Range::positive())
        .shown_default("2 particle_spacing")
        .doc("half-width of a depth gauge's bilinear tent"),
    s.gauge_half_width);
  v(Key("arrival_fraction")
        .in(Range{0.0, 1.0, true})
        .doc("arrival: the first time a probe reads this fraction of its measured peak"),
    s.arrival_fraction);
}

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, FreeOverfallKeys>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  using scenario::Range;
  v(Key("average_from")
        .unit("s")
        .in(Range::non_negative())
        .needed()
        .doc("time means start here, once the flow is established"),
    p.reference.average_from);
}

// A `reference.pressure_probes` or `reference.depth_gauges` entry, as the scenario gives it.
struct PressureProbeKeys {
  std::string column;
  Eigen::Vector3d at = Eigen::Vector3d::Zero();
};
struct DepthGaugeKeys {
  std::string column;
  Eigen::Vector2d at = Eigen::Vector2d::Zero();
};

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, PressureProbeKeys>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  v(Key("column").needed().doc("of the measured record"), p.column);
  v(Key("at").unit("m").needed().doc("world [x, y, z] of the sensor"), p.at);
}

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, DepthGaugeKeys>
void visit_parameters(P& p, V& v) {
  using scenario::Key;
  v(Key("column").needed().doc("of the measured record"), p.column);
  v(Key("at").unit("m").needed().doc("world [x, y] of the gauge; its depth is along z"), p.at);
}

}  // namespace cosim::mps
