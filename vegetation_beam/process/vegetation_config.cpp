#include "vegetation_config.hpp"

#include <fmt/format.h>

namespace cosim::vegetation {

using scenario::Range;

namespace {

// One entry of `plants`: a single plant, or a row of `count` equal plants `spacing` apart.
void parse_plant_group(scenario::Section& group, const BeamParameters& parameters,
                       std::vector<PlantSpec>& plants, BeamChecks& checks) {
  PlantSpec spec;
  spec.base = group.vector3("base");
  // World frame (docs/architecture.md): z is up, so plants stand along +z unless told otherwise.
  spec.direction = group.vector3("direction", Eigen::Vector3d::UnitZ());
  if (spec.direction.norm() == 0.0) group.fail("direction", "must not be zero");
  spec.length = group.number("length", Range::positive());
  spec.links = group.integer("links", 20, Range::between(1, 10000));
  spec.width = group.number("width", Range::positive());
  spec.thickness = group.number("thickness", Range::positive());
  spec.density = group.number("density", Range::positive());
  const bool has_bending = group.has("bending_stiffness");
  const bool has_axial = group.has("axial_stiffness");
  if (!has_bending || !has_axial) {
    spec.youngs_modulus = group.number("youngs_modulus", Range::positive());
  }
  if (has_bending) spec.bending_stiffness = group.number("bending_stiffness", Range::positive());
  if (has_axial) spec.axial_stiffness = group.number("axial_stiffness", Range::positive());
  const int count = group.integer("count", 1, Range::between(1, 1000000));
  const Eigen::Vector3d spacing = group.vector3("spacing", Eigen::Vector3d::Zero());
  if (count > 1 && spacing.norm() == 0.0) {
    group.fail("spacing", "a row of several plants needs a non-zero spacing");
  }
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
  parameters.fluid_density =
      section.number("fluid_density", parameters.fluid_density, Range::non_negative());
  parameters.drag_coefficient =
      section.number("drag_coefficient", parameters.drag_coefficient, Range::non_negative());
  parameters.added_mass_coefficient = section.number(
      "added_mass_coefficient", parameters.added_mass_coefficient, Range::non_negative());
  parameters.gravity = scene.world.gravity;  // the scene's one gravity (world.gravity)
  parameters.axial_damping_ratio = section.number(
      "axial_damping_ratio", parameters.axial_damping_ratio, Range::between(0.0, 10.0));
  parameters.bending_damping_ratio = section.number(
      "bending_damping_ratio", parameters.bending_damping_ratio, Range::between(0.0, 10.0));
  parameters.contact = section.flag("contact", parameters.contact);
  parameters.contact_stiffness =
      section.number("contact_stiffness", parameters.contact_stiffness, Range::non_negative());
  parameters.rigid = section.flag("rigid", parameters.rigid);
  // The Newmark average-acceleration scheme is unconditionally stable: factors above 1 trade
  // axial-strain accuracy for speed (seed 000: 10 to 100 beam steps per fluid step suffice).
  parameters.safety_factor =
      section.number("safety_factor", parameters.safety_factor, Range{0.0, 1000.0, true});
  parameters.max_substeps =
      section.integer("max_substeps", parameters.max_substeps, Range::between(1, 100000000));
  // Newton of each sub-step (PlantField::advance), per attempt. The tolerance is on the largest
  // position correction in link lengths: looser than 1e-3 of a link per sub-step it is no longer
  // small against the shapes it should resolve; the default 1e-10 is near round-off.
  parameters.newton_tolerance =
      section.number("newton_tolerance", parameters.newton_tolerance, Range{0.0, 1e-3, true});
  parameters.max_newton_iterations = section.integer(
      "max_newton_iterations", parameters.max_newton_iterations, Range::between(1, 1000));

  for (auto& group : section.list("plants"))
    parse_plant_group(group, parameters, config.plants, config.checks);
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
