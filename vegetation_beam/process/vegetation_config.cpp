#include "vegetation_config.hpp"

#include <fmt/format.h>

#include "cosim/scenario/parameter_reader.hpp"

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
  const int count = group.integer("count", 1, Range::between(1, 1000000));
  const Eigen::Vector3d spacing = group.vector3("spacing", Eigen::Vector3d::Zero());
  if (count > 1 && spacing.norm() == 0.0) {
    group.fail("spacing", "a row of several plants needs a non-zero spacing");
  }
  const double nodes = static_cast<double>(count) * (spec.links + 1.0);
  memory.add(group, count > 1 ? "count" : "links", estimated_memory_bytes(count, nodes),
             fmt::format("{} plants x {} links: {:.3g} nodes x {:g} B", count, spec.links, nodes,
                         kBytesPerPlantNode));
  parse_plant_checks(group, spec, parameters, static_cast<int>(plants.size()), count, checks);
  for (int i = 0; i < count; ++i) {
    PlantSpec plant = spec;
    plant.base = spec.base + i * spacing;
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
  parse_section_checks(section, config.plants, config.checks);

  config.output_interval =
      section.number("output_interval", scene_output_interval, Range::positive());

  if (section.has("canopy")) {
    auto canopy = section.child("canopy");
    CanopySettings settings;
    settings.psi_radius =
        canopy.number("psi_radius", 7.0 * config.plants.front().width, Range::positive());
    settings.streamwise = canopy.vector3("streamwise", settings.streamwise);
    if (settings.streamwise.norm() == 0.0) canopy.fail("streamwise", "must not be zero");
    settings.streamwise.normalize();
    settings.amplitude_from = canopy.number("amplitude_from", 0.0, Range::non_negative());
    settings.tip_interval =
        canopy.number("tip_interval", config.output_interval, Range::positive());
    config.canopy = settings;
  }
  if (section.has("reference")) {
    auto reference = section.child("reference");
    reference.choice("kind", {"elastica_uniform_flow"});
    ElasticaReference elastica;
    elastica.plant = reference.integer("plant", 0, Range::between(0, 1e9));
    if (elastica.plant >= static_cast<int>(config.plants.size())) {
      reference.fail("plant", fmt::format("there are only {} plants", config.plants.size()));
    }
    elastica.velocity = reference.vector3("velocity");
    elastica.average_over = reference.number("average_over", Range::positive());
    config.elastica_reference = elastica;
  }
  return config;
}

}  // namespace cosim::vegetation
