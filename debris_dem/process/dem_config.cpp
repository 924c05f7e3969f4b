#include "dem_config.hpp"

#include <algorithm>

namespace cosim::dem {

using scenario::Range;

namespace {

Material parse_material(scenario::Section section, Material defaults) {
  Material m = defaults;
  m.density = section.number("density", m.density, Range::positive());
  m.normal_stiffness = section.number("normal_stiffness", m.normal_stiffness, Range::positive());
  m.tangential_stiffness =
      section.number("tangential_stiffness", m.tangential_stiffness, Range::non_negative());
  m.damping_ratio = section.number("damping_ratio", m.damping_ratio, Range::between(0.0, 1.0));
  m.restitution = section.number("restitution", m.restitution, Range::between(0.0, 1.0));
  m.friction = section.number("friction", m.friction, Range::non_negative());
  return m;
}

}  // namespace

DebrisConfig parse_config(scenario::Section& section, double scene_output_interval) {
  DebrisConfig config;
  DemParameters& p = config.parameters;
  config.slope_degrees = section.number("slope_degrees", 0.0, Range::between(0.0, 60.0));
  const double g = section.number("gravity_magnitude", 9.81, Range::non_negative());
  p.gravity = slope_gravity(config.slope_degrees, g);
  p.fluid_density = section.number("fluid_density", p.fluid_density, Range::non_negative());
  p.drag_coefficient_sphere =
      section.number("drag_coefficient_sphere", p.drag_coefficient_sphere, Range::non_negative());
  p.drag_coefficient_cylinder = section.number("drag_coefficient_cylinder",
                                               p.drag_coefficient_cylinder, Range::non_negative());
  p.user_dt = section.number("substep", 1.0e-5, Range::non_negative());
  p.safety_factor = section.number("safety_factor", p.safety_factor, Range{0.0, 1.0, true});
  p.list_margin = section.number("list_margin", p.list_margin, Range::positive());
  p.list_reset_interval =
      section.number("list_reset_interval", p.list_reset_interval, Range::positive());
  p.max_overlap_ratio =
      section.number("max_overlap_ratio", p.max_overlap_ratio, Range{0.0, 1.0, true});

  Material debris_defaults;  // seed 004 table 3: s.g. 1.9
  Material log_defaults;
  log_defaults.density = 800.0;  // s.g. 0.8
  auto materials = section.optional_child("materials");
  config.debris = parse_material(materials.optional_child("debris"), debris_defaults);
  config.logs = parse_material(materials.optional_child("logs"), log_defaults);
  config.structure = parse_material(materials.optional_child("structure"), debris_defaults);

  auto flume = section.child("flume");
  config.flume.length = flume.number("length", Range::positive());
  config.flume.width = flume.number("width", Range::positive());
  config.flume.wall_height = flume.number("wall_height", Range::positive());
  config.flume.upstream_wall = flume.flag("upstream_wall", true);

  if (section.has("bed_roughness")) {
    auto rough = section.child("bed_roughness");
    RoughnessSettings r;
    r.x0 = rough.number("x0", Range::non_negative());
    r.x1 = rough.number("x1", Range::positive());
    if (r.x1 <= r.x0) rough.fail("x1", "must exceed x0");
    r.d_min = rough.number("d_min", Range::positive());
    r.d_max = rough.number("d_max", Range::positive());
    if (r.d_max < r.d_min) rough.fail("d_max", "must not be below d_min");
    r.seed = static_cast<unsigned>(rough.integer("seed", 1, Range::non_negative()));
    config.roughness = r;
  }
  if (section.has("dam")) {
    auto dam = section.child("dam");
    GridDamSpec spec;
    spec.x = dam.number("x", Range::positive());
    if (spec.x >= config.flume.length) dam.fail("x", "the dam must stand inside the flume");
    spec.width = config.flume.width;
    spec.column_diameter = dam.number("column_diameter", spec.column_diameter, Range::positive());
    spec.horizontal_gap = dam.number("horizontal_gap", Range::positive());
    spec.vertical_gap = dam.number("vertical_gap", 0.0, Range::non_negative());
    spec.height = dam.number("height", config.flume.wall_height, Range::positive());
    config.dam = spec;
  }

  auto packing = section.child("packing");
  config.packing.box_min = packing.vector3("box_min");
  config.packing.box_max = packing.vector3("box_max");
  if ((config.packing.box_max - config.packing.box_min).minCoeff() <= 0) {
    packing.fail("box_max", "must exceed box_min in x, y and z");
  }
  for (auto& entry : packing.list("spheres")) {
    SphereClass sphere_class{entry.number("diameter", Range::positive()),
                             entry.integer("count", Range::between(0, 1e7))};
    config.sphere_classes.push_back(sphere_class);
    for (int i = 0; i < sphere_class.count; ++i) {
      config.packing.sphere_diameters.push_back(sphere_class.diameter);
    }
  }
  config.packing.log_count = packing.integer("log_count", 0, Range::between(0, 1e6));
  config.packing.log_diameter = packing.number("log_diameter", 0.01, Range::positive());
  config.packing.log_length = packing.number("log_length", 0.1, Range::positive());
  config.packing.seed = static_cast<unsigned>(packing.integer("seed", 1, Range::non_negative()));
  if (config.packing.sphere_diameters.empty() && config.packing.log_count == 0) {
    packing.fail("spheres", "no debris to pack");
  }

  auto gate = section.child("gate");
  config.gate_x = gate.number("x", Range::positive());
  if (config.gate_x < config.packing.box_max.x()) {
    gate.fail("x", "the gate must stand downstream of the packing box");
  }
  config.settle_time = gate.number("settle_time", config.settle_time, Range::non_negative());

  // Debris that passes the dam leaves the flume's end and falls freely; only elements thrown
  // sideways or upstream out of the flume, or falling for minutes, are errors.
  const double margin = 1.0;
  p.domain_min = Eigen::Vector3d(-margin, -margin, -100.0);
  p.domain_max = Eigen::Vector3d(config.flume.length + 100.0, config.flume.width + margin,
                                 config.flume.wall_height + 10 * margin);
  config.output_interval =
      section.number("output_interval", scene_output_interval, Range::positive());
  return config;
}

}  // namespace cosim::dem
