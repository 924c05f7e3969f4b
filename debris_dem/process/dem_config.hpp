// The `debris_dem` section of a scenario: the flume, bed roughness, check dam, debris packing
// behind a gate, materials and numerical parameters (seed 004 table 3 as defaults).
#pragma once

#include <optional>
#include <vector>

#include "cosim/debris_dem/dem_world.hpp"
#include "cosim/debris_dem/scenes.hpp"
#include "cosim/scenario/section.hpp"

namespace cosim::dem {

struct SphereClass {
  double diameter = 0;
  int count = 0;
};

struct RoughnessSettings {
  double x0 = 0, x1 = 0, d_min = 0, d_max = 0;
  unsigned seed = 1;
};

struct DebrisConfig {
  DemParameters parameters;
  double slope_degrees = 0;
  Material debris, logs, structure;
  FlumeSpec flume;
  std::optional<RoughnessSettings> roughness;
  std::optional<GridDamSpec> dam;
  PackingSpec packing;
  std::vector<SphereClass> sphere_classes;
  double gate_x = 0;         // the packing is held upstream of a gate at this x
  double settle_time = 0.5;  // seconds of free fall behind the gate before the run starts
  double output_interval = 0;
};

DebrisConfig parse_config(scenario::Section& section, double scene_output_interval);

}  // namespace cosim::dem
