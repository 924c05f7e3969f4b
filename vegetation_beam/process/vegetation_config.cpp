#include "vegetation_config.hpp"

#include <fmt/format.h>

#include "cosim/scenario/parameter_reader.hpp"
#include "section_keys.hpp"

namespace cosim::vegetation {

using scenario::Range;

namespace {

// One entry of `plants`: a single plant, or a row of `count` equal plants `spacing` apart.
void parse_plant_group(scenario::Section& group, const BeamParameters& parameters,
                       std::vector<PlantSpec>& plants, BeamChecks& checks,
                       scenario::MemoryBudget& memory) {
  // World frame (docs/architecture.md): z is up, so plants stand along +z unless told otherwise.
  PlantSpec spec = scenario_plant_defaults();
  scenario::read_parameters(group, spec);  // the keys declared in plant_field.hpp
  PlantRow row;
  scenario::read_parameters(group, row);  // section_keys.hpp
  const double nodes = static_cast<double>(row.count) * (spec.links + 1.0);
  memory.add(group, row.count > 1 ? "count" : "links", estimated_memory_bytes(row.count, nodes),
             fmt::format("{} plants x {} links: {:.3g} nodes x {:g} B", row.count, spec.links,
                         nodes, kBytesPerPlantNode));
  parse_plant_checks(group, spec, parameters, static_cast<int>(plants.size()), row.count, checks);
  for (int i = 0; i < row.count; ++i) {
    PlantSpec plant = spec;
    plant.base = spec.base + i * row.spacing;
    plants.push_back(plant);
  }
}

}  // namespace

VegetationConfig parse_config(scenario::Section& section, const scenario::Scene& scene) {
  const double scene_output_interval = scene.output_interval;
  VegetationConfig config;
  BeamParameters& parameters = config.parameters;
  scenario::read_parameters(section, parameters);  // the keys declared in plant_field.hpp
  parameters.gravity = scene.world.gravity;        // the scene's one gravity (world.gravity)

  scenario::MemoryBudget memory("vegetation_beam");
  for (auto& group : section.list("plants"))
    parse_plant_group(group, parameters, config.plants, config.checks, memory);
  if (config.plants.empty()) section.fail("plants", "needs at least one plant");
  if (scene.coupling.interface.resolved_plants) {
    // The fluid's wall particles follow one chain of nodes.
    if (config.plants.size() != 1) {
      section.fail("plants", "coupling.resolved_plants takes one plant");
    }
    // The fluid carries the drag and the added mass through its pressure on the plant.
    parameters.drag_coefficient = 0.0;
    parameters.added_mass_coefficient = 0.0;
  }
  parse_section_checks(section, config.plants, config.checks);

  config.output_interval =
      section.number("output_interval", scene_output_interval, Range::positive());

  if (section.has("canopy")) {
    auto canopy = section.child("canopy");
    CanopySettings settings;
    settings.psi_radius = 7.0 * config.plants.front().width;
    settings.tip_interval = config.output_interval;
    scenario::read_parameters(canopy, settings);
    settings.streamwise.normalize();
    config.canopy = settings;
  }
  if (section.has("reference")) {
    auto reference = section.child("reference");
    ElasticaReference elastica;
    scenario::read_parameters(reference, elastica);
    if (elastica.plant >= static_cast<int>(config.plants.size())) {
      reference.fail("plant", fmt::format("there are only {} plants", config.plants.size()));
    }
    config.elastica_reference = elastica;
  }
  return config;
}

}  // namespace cosim::vegetation
