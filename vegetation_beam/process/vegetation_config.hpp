// The `vegetation_beam` section of a scenario: plants, beam and fluid parameters, outputs, and
// the reference the run is checked against.
#pragma once

#include <optional>
#include <vector>

#include "beam_checks.hpp"
#include "cosim/scenario/scene.hpp"
#include "cosim/scenario/section.hpp"
#include "cosim/vegetation_beam/plant_field.hpp"

namespace cosim::vegetation {

// The steady bent shape of one plant in a uniform stream, from the large-deflection elastica
// (see elastica.hpp): the run's time-averaged tip position is compared with it.
enum class ReferenceKind { elastica_uniform_flow };
inline constexpr scenario::Choices<ReferenceKind, 1> kReferenceKinds{
    {{"elastica_uniform_flow", ReferenceKind::elastica_uniform_flow}}};

struct ElasticaReference {
  ReferenceKind kind = ReferenceKind::elastica_uniform_flow;
  int plant = 0;
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  // the uniform stream
  double average_over = 0.0;  // seconds at the end of the run over which the tip is averaged
};

// Canopy measures of seed 000 section 4: the vegetation density change psi (eq. 24) in the
// output frames, the honami amplitude of every plant's tip and the tip time series (tips.csv:
// streamwise, tip_heights.csv: along the plant's unstressed direction, as in seed 000 fig. 9).
struct CanopySettings {
  double psi_radius = 0.0;  // seed 000: 7 d_veg
  Eigen::Vector3d streamwise = Eigen::Vector3d::UnitX();
  double amplitude_from = 0.0;  // tip extremes are tracked from this time on [s]
  double tip_interval = 0.0;    // [s] between tip rows; default: the output_interval
};

// One `plants` entry is a row of `count` equal plants, `spacing` apart (besides its PlantSpec).
struct PlantRow {
  int count = 1;
  Eigen::Vector3d spacing = Eigen::Vector3d::Zero();
};

struct VegetationConfig {
  std::vector<PlantSpec> plants;
  BeamParameters parameters;
  double output_interval = 0.0;
  std::optional<ElasticaReference> elastica_reference;
  std::optional<CanopySettings> canopy;
  BeamChecks checks;  // point loads, plucks, static start, modal output
};

// `output_interval` is the scene's default for the section's own `output_interval`.
VegetationConfig parse_config(scenario::Section& section, const scenario::Scene& scene);

}  // namespace cosim::vegetation
