// The `debris_dem` section of a scenario: the structure (the seed 004 flume with bed roughness,
// check dam and a gated debris packing, and/or a closed box open at the top), explicit elements,
// materials, the fluid force model and numerical parameters (seed 004 table 3 as defaults).
//
// Structure (each optional; something must move: a packing or elements):
//   flume: {length, width, wall_height, upstream_wall}; bed_roughness, dam: need the flume
//   box: {min: [x, y, z], max: [x, y, z]}       floor and four walls, open top; max > min
//   packing: {...}; gate: {x, settle_time}       the gate needs the flume and the packing
//   elements: [{kind: sphere | log, center, diameter > 0, length > 0 (logs), axis != 0 (logs),
//               density > 0, velocity (default 0)}]   contact constants of materials.debris/logs
// Fluid forces (DemParameters, keys declared in dem_parameters.hpp; `cosim keys debris_dem`):
//   drag_law: seed004 (default) | schiller_naumann
//   drag_coefficient_sphere, drag_coefficient_cylinder >= 0      seed004 only
//   fluid_viscosity in [1e-7, 1e6] Pa s (default 1e-3)            schiller_naumann only
//   voidage_correction (default false), voidage_radius > 0 m      schiller_naumann only
//   fluid_acceleration_force, added_mass    default true for schiller_naumann, false for seed004
//   added_mass_coefficient (sphere, 0.5), added_mass_coefficient_log_normal (1),
//   added_mass_coefficient_log_axial (0), each in [0, 5]          with added_mass only
#pragma once

#include <optional>
#include <vector>

#include "cosim/debris_dem/dem_world.hpp"
#include "cosim/debris_dem/scenes.hpp"
#include "cosim/scenario/scene.hpp"
#include "cosim/scenario/section.hpp"
#include "element_reference.hpp"

namespace cosim::dem {

struct SphereClass {
  double diameter = 0;
  int count = 0;
};

struct RoughnessSettings {
  double x0 = 0, x1 = 0, d_min = 0, d_max = 0;
  unsigned seed = 1;
};

struct BoxSettings {
  Eigen::Vector3d min = Eigen::Vector3d::Zero();
  Eigen::Vector3d max = Eigen::Vector3d::Zero();
};

// One element of the `elements:` list: a sphere, or a log (flat-ended cylinder).
struct ElementSettings {
  bool log = false;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double diameter = 0;
  double length = 0;                                // logs
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();  // logs, unit
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  Material material;  // materials.debris (spheres) or materials.logs, with this density
};

struct GateSettings {
  double x = 0;              // the packing is held upstream of a gate at this x
  double settle_time = 0.5;  // seconds of free fall behind the gate before the run starts
};

struct DebrisConfig {
  DemParameters parameters;
  Material debris, logs, structure;
  std::optional<FlumeSpec> flume;
  std::optional<RoughnessSettings> roughness;  // needs the flume
  std::optional<GridDamSpec> dam;              // needs the flume
  std::optional<BoxSettings> box;
  std::optional<PackingSpec> packing;
  std::vector<SphereClass> sphere_classes;
  std::optional<GateSettings> gate;  // needs the flume and the packing
  std::vector<ElementSettings> elements;
  double output_interval = 0;
  std::optional<ElementReferenceSettings> reference;  // single-element scenes
};

// `scene`: the top level, already read (output interval, the world's gravity).
DebrisConfig parse_config(scenario::Section& section, const scenario::Scene& scene);

}  // namespace cosim::dem
