#include "dem_config.hpp"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <string>
#include <tuple>
#include <utility>

#include "cosim/scenario/parameter_reader.hpp"
#include "cosim/scenario/stl_section.hpp"
#include "structure_keys.hpp"

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
  scenario::read_parameters(flume, spec);  // the keys declared in structure_keys.hpp
  config.flume = spec;
  if (section.has("bed_roughness")) {
    auto rough = section.child("bed_roughness");
    RoughnessSettings r;
    scenario::read_parameters(rough, r);
    config.roughness = r;
  }
  if (section.has("dam")) {
    auto dam = section.child("dam");
    GridDamSpec dam_spec;
    dam_spec.width = spec.width;
    dam_spec.height = spec.wall_height;
    scenario::read_parameters(dam, dam_spec);
    if (dam_spec.x >= spec.length) dam.fail("x", "the dam must stand inside the flume");
    config.dam = dam_spec;
  }
}

// The random packing of seed 004 section 4.1(2), and the gate that holds it while it settles.
void parse_packing(scenario::Section& section, DebrisConfig& config) {
  if (!section.has("packing")) {
    forbid(section, "gate", "a packing");
    return;
  }
  auto packing = section.child("packing");
  PackingSpec spec;
  scenario::read_parameters(packing, spec);
  scenario::MemoryBudget memory("debris_dem");
  for (auto& entry : packing.list("spheres")) {
    SphereClass sphere_class;
    scenario::read_parameters(entry, sphere_class);
    memory.add(entry, "count", sphere_class.count * kBytesPerElement,
               fmt::format("{} spheres x {:g} B", sphere_class.count, kBytesPerElement));
    config.sphere_classes.push_back(sphere_class);
    for (int i = 0; i < sphere_class.count; ++i) {
      spec.sphere_diameters.push_back(sphere_class.diameter);
    }
  }
  memory.add(packing, "log_count", spec.log_count * kBytesPerElement,
             fmt::format("{} logs x {:g} B", spec.log_count, kBytesPerElement));
  if (spec.sphere_diameters.empty() && spec.log_count == 0) {
    packing.fail("spheres", "no debris to pack");
  }
  config.packing = spec;
  if (!section.has("gate")) return;
  auto gate = section.child("gate");
  if (!config.flume) gate.fail("x", "the gate spans a flume: give one");
  GateSettings settings;
  scenario::read_parameters(gate, settings);
  if (settings.x < spec.box_max.x()) {
    gate.fail("x", "the gate must stand downstream of the packing box");
  }
  config.gate = settings;
}

// A closed box of wall triangles, open at the top.
void parse_box(scenario::Section& section, DebrisConfig& config) {
  if (!section.has("box")) return;
  auto box = section.child("box");
  BoxSettings settings;
  scenario::read_parameters(box, settings);
  config.box = settings;
}

void parse_elements(scenario::Section& section, DebrisConfig& config) {
  if (!section.has("elements")) return;
  for (auto& entry : section.list("elements")) {
    ElementSettings e;
    scenario::read_parameters(entry, e);
    if (e.is_log()) e.axis.normalize();
    e.material = e.is_log() ? config.logs : config.debris;
    e.material.density = e.density;
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
  // STL walls: their bounds grown like a box's. Without a flume or box the default (+-1e6 m)
  // stays, as walls alone may well be open to one side.
  if (!config.walls.empty() && (config.flume || config.box)) {
    Eigen::AlignedBox3d bounds;
    for (const auto& mesh : config.walls) {
      for (const auto& t : mesh) bounds.extend(t.a).extend(t.b).extend(t.c);
    }
    p.domain_min = p.domain_min.cwiseMin(bounds.min() - Eigen::Vector3d::Constant(margin));
    p.domain_max =
        p.domain_max.cwiseMax(bounds.max() + Eigen::Vector3d(margin, margin, 10 * margin));
  }
}

// What each reference needs of the scene.
void check_reference(scenario::Section& reference, const ElementReferenceSettings& r,
                     const DebrisConfig& config) {
  const DemParameters& p = config.parameters;
  const std::string kind(scenario::choice_name(kElementReferenceKinds, r.kind));
  if (r.kind == ReferenceKind::hindered) {
    if (!config.packing || !config.elements.empty() || config.packing->log_count > 0 ||
        config.sphere_classes.size() != 1 || p.drag_law != DragLaw::kSchillerNaumann) {
      reference.fail("kind",
                     "hindered settling needs a packing of one sphere class, no logs, no "
                     "explicit elements, and drag_law: schiller_naumann");
    }
    return;
  }
  if (config.elements.size() != 1 || config.packing) {
    reference.fail("kind", "a " + kind + " reference needs exactly one element and no packing");
  }
  if (r.kind == ReferenceKind::settling && p.drag_law != DragLaw::kSchillerNaumann) {
    reference.fail("kind",
                   "the settling reference is the Schiller-Naumann terminal velocity: "
                   "set drag_law: schiller_naumann");
  }
  const double ratio = config.elements.front().material.density / p.fluid_density;
  if (r.kind == ReferenceKind::settling && !(ratio > 1.0)) {
    reference.fail("kind",
                   "the element does not sink (density ratio " + std::to_string(ratio) + ")");
  }
  if (r.kind == ReferenceKind::floating && !(ratio > 0.0 && ratio < 1.0)) {
    reference.fail("kind",
                   "the element does not float (density ratio " + std::to_string(ratio) + ")");
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
  config.walls = scenario::read_stl_list(section, "walls");
  parse_packing(section, config);
  parse_elements(section, config);
  if (!config.packing && config.elements.empty()) {
    section.fail("elements", "nothing moves: give a packing or elements");
  }
  set_domain(config);
  if (section.has("front_gauge_x")) {
    if (!config.dam) section.fail("front_gauge_x", "only used with a dam");
    const double x = section.number("front_gauge_x", Range::positive());
    if (config.gate && x <= config.gate->x) {
      section.fail("front_gauge_x", "must lie downstream of the gate");
    }
    if (x >= config.dam->x) section.fail("front_gauge_x", "must lie upstream of the dam");
    config.front_gauge_x = x;
  }
  config.output_interval =
      section.number("output_interval", scene_output_interval, Range::positive());
  if (section.has("reference")) {
    auto reference = section.child("reference");
    ElementReferenceSettings r;
    scenario::read_parameters(reference, r);
    check_reference(reference, r, config);
    config.reference = r;
  }
  return config;
}

}  // namespace cosim::dem
