// Scenario keys for the standard beam checks (references/cantilever.md): point and tip loads, a
// pluck (released static deflection, or a start in the velocity of one linear mode), a static
// start, and modal output. Parsed with the rest of the vegetation_beam section; applied to the
// plant field before window 0.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <vector>

#include "cosim/scenario/section.hpp"
#include "cosim/vegetation_beam/plant_field.hpp"

namespace cosim::vegetation {

// A constant force on one node for the whole run (plants[i].point_loads).
struct PointLoad {
  int plant = 0;
  int node = 0;                                     // local index, 1 .. links
  Eigen::Vector3d force = Eigen::Vector3d::Zero();  // N, world frame
};

// plants[i].pluck: the plant starts either in static equilibrium with an extra tip force that is
// released at t = 0, or in its rest shape moving in the shape of linear mode `mode`.
struct Pluck {
  int plant = 0;
  Eigen::Vector3d tip_force = Eigen::Vector3d::Zero();     // N, released at t = 0
  int mode = 1;                                            // 1-based, distinct frequencies
  Eigen::Vector3d tip_velocity = Eigen::Vector3d::Zero();  // m/s at the tip
  std::string where;  // "file:line: key '...'" of the pluck, for errors found at the start
};

// The keys of one plants[i].point_loads entry and of plants[i].pluck, as the scenario gives
// them (section_keys.hpp declares them).
struct PointLoadSettings {
  double at = 0.0;                                  // fraction of the length from the base
  Eigen::Vector3d force = Eigen::Vector3d::Zero();  // N, world frame
};
struct PluckSettings {
  Eigen::Vector3d tip_force = Eigen::Vector3d::Zero();     // N
  Eigen::Vector3d tip_velocity = Eigen::Vector3d::Zero();  // m/s
  int mode = 1;
};

struct BeamChecks {
  std::vector<PointLoad> point_loads;
  std::vector<Pluck> plucks;
  bool static_solve = false;  // start from static equilibrium (still water, fully submerged)
  int modes = 0;              // linear natural frequencies written per plant (0: none)
};

// The check keys of one `plants` entry, describing plants first_plant .. first_plant + count - 1
// (all like `spec`). A velocity pluck is tried on the straight plant here, so that a tip
// velocity the mode cannot produce is an error of the scenario file.
void parse_plant_checks(scenario::Section& group, const PlantSpec& spec,
                        const BeamParameters& parameters, int first_plant, int count,
                        BeamChecks& checks);
// The section-level keys static_solve and modes (read after `plants`).
void parse_section_checks(scenario::Section& section, const std::vector<PlantSpec>& plants,
                          BeamChecks& checks);

struct StartReport {
  int static_iterations = 0;  // Newton iterations of the static solve (0: none)
  std::vector<Eigen::Vector3d> pluck_tip_velocities;  // per pluck, the tip velocity set
};

// Per node of the field, the sum of the point loads.
std::vector<Eigen::Vector3d> point_load_forces(const PlantField& field, const BeamChecks& checks);

// Applies the checks to a freshly built field: point loads; the static solve (static_solve, or
// plants plucked by a tip force: weight, buoyancy, point loads and the pluck forces, no flow;
// plants neither plucked nor statically solved keep their straight shape); the release of the
// pluck forces; the modal velocities. Throws std::invalid_argument naming the pluck's key when a
// mode cannot give the asked tip velocity about the start shape (within 1 %).
StartReport prepare_start(PlantField& field, const BeamChecks& checks);

// Lowest `count` distinct linear natural frequencies (Hz) of every plant about its current
// shape, and their table modes.csv: plant, mode, frequency_hz.
std::vector<std::vector<double>> modal_frequencies(const PlantField& field, int count);
void write_modes(const std::filesystem::path& file,
                 const std::vector<std::vector<double>>& frequencies);

}  // namespace cosim::vegetation
