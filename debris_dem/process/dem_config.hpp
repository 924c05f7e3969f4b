// The `debris_dem` section of a scenario: the structure (the seed 004 flume with bed roughness,
// check dam and a gated debris packing, and/or a closed box open at the top), explicit elements,
// materials, the fluid force model and numerical parameters (seed 004 table 3 as defaults).
//
// Structure (each optional; something must move: a packing or elements): flume (bed_roughness
// and dam need it), box, packing (a gate needs it and the flume), elements. Every key, its range
// and its rules are declared once: DemParameters and Material in dem_parameters.hpp, the nested
// keys in structure_keys.hpp (`cosim keys debris_dem`, docs/scenario-keys.md).
#pragma once

#include <optional>
#include <vector>

#include "cosim/debris_dem/dem_world.hpp"
#include "cosim/debris_dem/scenes.hpp"
#include "cosim/scenario/scene.hpp"
#include "cosim/scenario/section.hpp"
#include "cosim/scenario/stl.hpp"
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

enum class ElementShape { sphere, log };
inline constexpr scenario::Choices<ElementShape, 2> kElementShapes{
    {{"sphere", ElementShape::sphere}, {"log", ElementShape::log}}};

// One element of the `elements:` list: a sphere, or a log (flat-ended cylinder).
struct ElementSettings {
  ElementShape shape = ElementShape::sphere;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double diameter = 0;
  double length = 0;                                // logs
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();  // logs, unit
  double density = 0;                               // kg/m^3
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  Material material;  // materials.debris (spheres) or materials.logs, with this density
  bool is_log() const { return shape == ElementShape::log; }
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
  // `walls`: STL files whose triangles are fixed wall triangles of the structure material
  // (cosim/scenario/stl_section.hpp; the fluid_mps `solids` read the same files) [m].
  std::vector<scenario::TriangleMesh> walls;
  // `front_gauge_x` (with a dam): when the debris front (99 % volume quantile) first passes this
  // x [m], the debris flow's length and shape are recorded (seed 004 fig. 13: about 1 m upstream
  // of the dam).
  std::optional<double> front_gauge_x;
  double output_interval = 0;
  std::optional<ElementReferenceSettings> reference;  // single-element scenes
};

// `scene`: the top level, already read (output interval, the world's gravity).
DebrisConfig parse_config(scenario::Section& section, const scenario::Scene& scene);

}  // namespace cosim::dem
