#include "beam_checks.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <stdexcept>

#include "cosim/scenario/parameter_reader.hpp"
#include "section_keys.hpp"

namespace cosim::vegetation {

namespace {

// The modes come from a dense generalized eigen solve of the 3 x links degrees of freedom of a
// plant (PlantField::linear_modes): 300 links (900 dofs) take about a second.
constexpr int kModalLinkLimit = 300;
// A mode must give the asked tip velocity to this fraction of its size.
constexpr double kTipVelocityTolerance = 0.01;

std::string format_vector(const Eigen::Vector3d& v) {
  return fmt::format("[{:.4g}, {:.4g}, {:.4g}]", v.x(), v.y(), v.z());
}

// The tip velocity mode `mode` of `field`'s plant gives when asked for `wanted`; empty if it is
// within tolerance, else the problem.
std::string mode_mismatch(PlantField& field, int plant, int mode, const Eigen::Vector3d& wanted) {
  const Eigen::Vector3d got = field.set_mode_velocity(plant, mode, wanted);
  if ((got - wanted).norm() <= kTipVelocityTolerance * wanted.norm()) return "";
  return fmt::format(
      "linear mode {} of plant {} moves its tip at best with {} m/s, not {} m/s (a bending mode "
      "moves the tip across the plant, an axial one along it)",
      mode, plant, format_vector(got), format_vector(wanted));
}

}  // namespace

void parse_plant_checks(scenario::Section& group, const PlantSpec& spec,
                        const BeamParameters& parameters, int first_plant, int count,
                        BeamChecks& checks) {
  if (group.has("point_loads")) {
    for (auto& entry : group.list("point_loads")) {
      PointLoadSettings load;
      scenario::read_parameters(entry, load);  // section_keys.hpp
      const int node = static_cast<int>(std::lround(load.at * spec.links));
      if (node == 0) {
        entry.fail("at", fmt::format("{} is nearest to the clamped base (node 0 of {} links), "
                                     "where a load does nothing",
                                     load.at, spec.links));
      }
      for (int i = 0; i < count; ++i)
        checks.point_loads.push_back({first_plant + i, node, load.force});
    }
  }
  if (!group.has("pluck")) return;
  auto pluck_section = group.child("pluck");
  PluckSettings settings;
  scenario::read_parameters(pluck_section, settings);
  Pluck pluck;
  pluck.tip_force = settings.tip_force;
  pluck.tip_velocity = settings.tip_velocity;
  pluck.mode = settings.mode;
  const bool moving = pluck.tip_velocity.norm() > 0;
  pluck.where = fmt::format("{}:{}: key '{}.{}'", pluck_section.file().string(),
                            pluck_section.line_of(moving ? "tip_velocity" : "tip_force"),
                            pluck_section.path(), moving ? "tip_velocity" : "tip_force");
  if (moving) {
    if (spec.links > kModalLinkLimit) {
      pluck_section.fail("tip_velocity",
                         fmt::format("a velocity pluck needs the plant's modes, computed "
                                     "densely: at most {} links (this plant has {})",
                                     kModalLinkLimit, spec.links));
    }
    PlantField straight({spec}, parameters);
    const std::string problem = mode_mismatch(straight, 0, pluck.mode, pluck.tip_velocity);
    if (!problem.empty()) pluck_section.fail("tip_velocity", problem);
  }
  for (int i = 0; i < count; ++i) {
    Pluck plant_pluck = pluck;
    plant_pluck.plant = first_plant + i;
    checks.plucks.push_back(plant_pluck);
  }
}

void parse_section_checks(scenario::Section& section, const std::vector<PlantSpec>& plants,
                          BeamChecks& checks) {
  scenario::read_parameters(section, checks);  // static_solve, modes (section_keys.hpp)
  for (std::size_t plant = 0; plant < plants.size() && checks.modes > 0; ++plant) {
    if (plants[plant].links > kModalLinkLimit) {
      section.fail("modes", fmt::format("plant {} has {} links; the modes are computed densely "
                                        "for at most {} links",
                                        plant, plants[plant].links, kModalLinkLimit));
    }
  }
}

std::vector<Eigen::Vector3d> point_load_forces(const PlantField& field, const BeamChecks& checks) {
  std::vector<Eigen::Vector3d> forces(field.node_count(), Eigen::Vector3d::Zero());
  for (const PointLoad& load : checks.point_loads)
    forces[field.node_range(load.plant).first + load.node] += load.force;
  return forces;
}

StartReport prepare_start(PlantField& field, const BeamChecks& checks) {
  StartReport report;
  const std::vector<Eigen::Vector3d> loads = point_load_forces(field, checks);
  std::vector<Eigen::Vector3d> held = loads;
  std::vector<char> deflect(field.plant_count(), checks.static_solve ? 1 : 0);
  for (const Pluck& pluck : checks.plucks) {
    if (pluck.tip_force.norm() == 0) continue;
    held[field.node_range(pluck.plant).second - 1] += pluck.tip_force;
    deflect[pluck.plant] = 1;
  }
  field.set_external_forces(held);
  if (std::find(deflect.begin(), deflect.end(), 1) != deflect.end()) {
    const std::vector<Eigen::Vector3d> straight = field.positions();
    report.static_iterations = field.solve_static().iterations;
    if (std::find(deflect.begin(), deflect.end(), 0) != deflect.end()) {
      std::vector<Eigen::Vector3d> positions = field.positions();
      for (int plant = 0; plant < field.plant_count(); ++plant) {
        if (deflect[plant]) continue;
        const auto [first, last] = field.node_range(plant);
        std::copy(straight.begin() + first, straight.begin() + last, positions.begin() + first);
      }
      field.set_state(positions, field.velocities());
    }
  }
  field.set_external_forces(loads);  // the pluck forces are released at t = 0
  for (const Pluck& pluck : checks.plucks) {
    if (pluck.tip_velocity.norm() == 0) continue;
    const std::string problem = mode_mismatch(field, pluck.plant, pluck.mode, pluck.tip_velocity);
    if (!problem.empty()) throw std::invalid_argument(pluck.where + ": " + problem);
    const auto [first, last] = field.node_range(pluck.plant);
    report.pluck_tip_velocities.push_back(field.velocities()[last - 1]);
    (void)first;
  }
  return report;
}

std::vector<std::vector<double>> modal_frequencies(const PlantField& field, int count) {
  std::vector<std::vector<double>> frequencies;
  if (count <= 0) return frequencies;
  for (int plant = 0; plant < field.plant_count(); ++plant) {
    if (field.specs()[plant].links > kModalLinkLimit) {
      throw std::invalid_argument(fmt::format(
          "vegetation_beam: modes: plant {} has {} links; modal output is computed densely for "
          "at most {} links",
          plant, field.specs()[plant].links, kModalLinkLimit));
    }
    frequencies.push_back(field.linear_natural_frequencies(plant, count));
  }
  return frequencies;
}

void write_modes(const std::filesystem::path& file,
                 const std::vector<std::vector<double>>& frequencies) {
  std::ofstream out(file);
  if (!out) throw std::runtime_error("vegetation_beam: cannot write " + file.string());
  out.precision(12);
  out << "plant,mode,frequency_hz\n";
  for (std::size_t plant = 0; plant < frequencies.size(); ++plant)
    for (std::size_t mode = 0; mode < frequencies[plant].size(); ++mode)
      out << plant << ',' << mode + 1 << ',' << frequencies[plant][mode] << '\n';
}

}  // namespace cosim::vegetation
