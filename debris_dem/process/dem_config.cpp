#include "dem_config.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <string>
#include <tuple>
#include <utility>

#include "cosim/scenario/parameter_reader.hpp"

namespace cosim::dem {

using scenario::Range;

namespace {

Material parse_material(scenario::Section section, Material defaults) {
  Material m = defaults;
  scenario::read_parameters(section, m);  // the keys declared in dem_parameters.hpp
  scenario::check_at_keys(section, [&] { validate_material(m); });
  return m;
}

// Fails for a key that only means something under another setting, instead of calling it
// unknown.
void forbid(scenario::Section& section, const std::string& key, const std::string& needs) {
  if (section.has(key)) section.fail(key, "only used with " + needs);
}

// The seed 004 flume with its bed roughness and check dam.
void parse_flume(scenario::Section& section, DebrisConfig& config) {
  if (!section.has("flume")) {
    for (const char* key : {"bed_roughness", "dam"}) forbid(section, key, "a flume");
    return;
  }
  auto flume = section.child("flume");
  FlumeSpec spec;
  spec.length = flume.number("length", Range::positive());
  spec.width = flume.number("width", Range::positive());
  spec.wall_height = flume.number("wall_height", Range::positive());
  spec.upstream_wall = flume.flag("upstream_wall", true);
  config.flume = spec;
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
    GridDamSpec dam_spec;
    dam_spec.x = dam.number("x", Range::positive());
    if (dam_spec.x >= spec.length) dam.fail("x", "the dam must stand inside the flume");
    dam_spec.width = spec.width;
    dam_spec.column_diameter =
        dam.number("column_diameter", dam_spec.column_diameter, Range::positive());
    dam_spec.horizontal_gap = dam.number("horizontal_gap", Range::positive());
    dam_spec.vertical_gap = dam.number("vertical_gap", 0.0, Range::non_negative());
    dam_spec.height = dam.number("height", spec.wall_height, Range::positive());
    config.dam = dam_spec;
  }
}

// The random packing of seed 004 section 4.1(2), and the gate that holds it while it settles.
// An axis-aligned box given by two corners; the second must exceed the first on every axis.
std::pair<Eigen::Vector3d, Eigen::Vector3d> parse_corners(scenario::Section& section,
                                                          const std::string& min_key,
                                                          const std::string& max_key) {
  const Eigen::Vector3d low = section.vector3(min_key);
  const Eigen::Vector3d high = section.vector3(max_key);
  if ((high - low).minCoeff() <= 0) {
    section.fail(max_key, "must exceed " + min_key + " in x, y and z");
  }
  return {low, high};
}

void parse_packing(scenario::Section& section, DebrisConfig& config) {
  if (!section.has("packing")) {
    forbid(section, "gate", "a packing");
    return;
  }
  auto packing = section.child("packing");
  PackingSpec spec;
  std::tie(spec.box_min, spec.box_max) = parse_corners(packing, "box_min", "box_max");
  scenario::MemoryBudget memory("debris_dem");
  for (auto& entry : packing.list("spheres")) {
    SphereClass sphere_class{entry.number("diameter", Range::positive()),
                             entry.integer("count", Range::between(0, 1e7))};
    memory.add(entry, "count", sphere_class.count * kBytesPerElement,
               fmt::format("{} spheres x {:g} B", sphere_class.count, kBytesPerElement));
    config.sphere_classes.push_back(sphere_class);
    for (int i = 0; i < sphere_class.count; ++i) {
      spec.sphere_diameters.push_back(sphere_class.diameter);
    }
  }
  spec.log_count = packing.integer("log_count", 0, Range::between(0, 1e6));
  memory.add(packing, "log_count", spec.log_count * kBytesPerElement,
             fmt::format("{} logs x {:g} B", spec.log_count, kBytesPerElement));
  spec.log_diameter = packing.number("log_diameter", 0.01, Range::positive());
  spec.log_length = packing.number("log_length", 0.1, Range::positive());
  spec.seed = static_cast<unsigned>(packing.integer("seed", 1, Range::non_negative()));
  if (spec.sphere_diameters.empty() && spec.log_count == 0) {
    packing.fail("spheres", "no debris to pack");
  }
  config.packing = spec;
  if (!section.has("gate")) return;
  auto gate = section.child("gate");
  if (!config.flume) gate.fail("x", "the gate spans a flume: give one");
  GateSettings settings;
  settings.x = gate.number("x", Range::positive());
  if (settings.x < spec.box_max.x()) {
    gate.fail("x", "the gate must stand downstream of the packing box");
  }
  settings.settle_time = gate.number("settle_time", settings.settle_time, Range::non_negative());
  config.gate = settings;
}

// A closed box of wall triangles, open at the top.
void parse_box(scenario::Section& section, DebrisConfig& config) {
  if (!section.has("box")) return;
  auto box = section.child("box");
  BoxSettings settings;
  std::tie(settings.min, settings.max) = parse_corners(box, "min", "max");
  config.box = settings;
}

void parse_elements(scenario::Section& section, DebrisConfig& config) {
  if (!section.has("elements")) return;
  for (auto& entry : section.list("elements")) {
    ElementSettings e;
    e.log = entry.choice("kind", {"sphere", "log"}) == "log";
    e.center = entry.vector3("center");
    e.diameter = entry.number("diameter", Range::positive());
    if (e.log) {
      e.length = entry.number("length", Range::positive());
      e.axis = entry.vector3("axis");
      if (!(e.axis.norm() > 0.0)) entry.fail("axis", "must not be the zero vector");
      e.axis.normalize();
    } else {
      forbid(entry, "length", "kind: log");
      forbid(entry, "axis", "kind: log");
    }
    e.material = e.log ? config.logs : config.debris;
    e.material.density = entry.number("density", Range::positive());
    e.velocity = entry.vector3("velocity", Eigen::Vector3d::Zero());
    if (config.box && ((e.center.array() < config.box->min.array()).any() ||
                       (e.center.array() > config.box->max.array()).any())) {
      entry.fail("center", "lies outside the box");
    }
    config.elements.push_back(e);
  }
}

// Elements that leave the structure by far are errors; debris that passes a flume's dam leaves
// its end and falls freely, so the flume's domain reaches far downstream and down.
void set_domain(DebrisConfig& config) {
  DemParameters& p = config.parameters;
  const double margin = 1.0;
  if (config.flume) {
    p.domain_min = Eigen::Vector3d(-margin, -margin, -100.0);
    p.domain_max = Eigen::Vector3d(config.flume->length + 100.0, config.flume->width + margin,
                                   config.flume->wall_height + 10 * margin);
  }
  if (config.box) {
    const Eigen::Vector3d low = config.box->min - Eigen::Vector3d::Constant(margin);
    const Eigen::Vector3d high = config.box->max + Eigen::Vector3d(margin, margin, 10 * margin);
    p.domain_min = config.flume ? Eigen::Vector3d(p.domain_min.cwiseMin(low)) : low;
    p.domain_max = config.flume ? Eigen::Vector3d(p.domain_max.cwiseMax(high)) : high;
  }
}

}  // namespace

DebrisConfig parse_config(scenario::Section& section, const scenario::Scene& scene) {
  const double scene_output_interval = scene.output_interval;
  DebrisConfig config;
  DemParameters& p = config.parameters;
  p.gravity = scene.world.gravity;  // the scene's one gravity (a flume: world.slope_degrees)
  // Drag law, fluid forces and numerics: the keys declared in dem_parameters.hpp.
  scenario::read_parameters(section, p);
  scenario::check_at_keys(section, [&] { validate_parameters(p); });

  auto materials = section.optional_child("materials");
  config.debris = parse_material(materials.optional_child("debris"), default_debris_material());
  config.logs = parse_material(materials.optional_child("logs"), default_log_material());
  config.structure =
      parse_material(materials.optional_child("structure"), default_debris_material());

  parse_flume(section, config);
  parse_box(section, config);
  parse_packing(section, config);
  parse_elements(section, config);
  if (!config.packing && config.elements.empty()) {
    section.fail("elements", "nothing moves: give a packing or elements");
  }
  set_domain(config);
  config.output_interval =
      section.number("output_interval", scene_output_interval, Range::positive());
  if (section.has("reference")) {
    auto reference = section.child("reference");
    ElementReferenceSettings r;
    r.kind = reference.choice("kind", {"settling", "floating", "hindered"});
    if (r.kind == "hindered") {
      if (!config.packing || !config.elements.empty() || config.packing->log_count > 0 ||
          config.sphere_classes.size() != 1 || p.drag_law != DragLaw::kSchillerNaumann) {
        reference.fail("kind",
                       "hindered settling needs a packing of one sphere class, no logs, no "
                       "explicit elements, and drag_law: schiller_naumann");
      }
      r.average_from = reference.number("average_from", 0.0, Range::non_negative());
      config.reference = r;
    } else {
      if (config.elements.size() != 1 || config.packing) {
        reference.fail("kind",
                       "a " + r.kind + " reference needs exactly one element and no packing");
      }
      if (r.kind == "settling" && p.drag_law != DragLaw::kSchillerNaumann) {
        reference.fail("kind",
                       "the settling reference is the Schiller-Naumann terminal velocity: "
                       "set drag_law: schiller_naumann");
      }
      const double ratio = config.elements.front().material.density / p.fluid_density;
      if (r.kind == "settling" && !(ratio > 1.0)) {
        reference.fail("kind",
                       "the element does not sink (density ratio " + std::to_string(ratio) + ")");
      }
      if (r.kind == "floating" && !(ratio > 0.0 && ratio < 1.0)) {
        reference.fail("kind",
                       "the element does not float (density ratio " + std::to_string(ratio) + ")");
      }
      r.average_from = reference.number("average_from", 0.0, Range::non_negative());
      config.reference = r;
    }
  }
  return config;
}

}  // namespace cosim::dem
