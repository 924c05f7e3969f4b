// The vegetation_beam process: connects the plant library to the coupler. Each window it takes
// the ambient flow at its nodes, sub-cycles the plants through the window and returns positions,
// velocities and the mean drag; it writes plant shapes for ParaView and reports the tip metrics.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <stdexcept>

#include "cosim/coupler/links.hpp"
#include "cosim/coupler/metrics.hpp"
#include "cosim/coupler/process_main.hpp"
#include "cosim/output/point_series.hpp"
#include "cosim/vegetation_beam/canopy_metrics.hpp"
#include "elastica.hpp"
#include "vegetation_config.hpp"

namespace {

using namespace cosim;

output::PointFrame make_frame(const vegetation::PlantField& field,
                              const std::vector<double>* initial_density = nullptr,
                              double psi_radius = 0.0) {
  output::PointFrame frame;
  if (initial_density) {
    frame.scalars["psi"] = vegetation::vegetation_density_change(
        vegetation::vegetation_number_density(field.positions(), psi_radius), *initial_density);
  }
  frame.time = field.time();
  frame.positions = field.positions();
  frame.vectors["velocity"] = field.velocities();
  frame.vectors["drag"] = field.window_mean_drag();
  auto& plant_label = frame.labels["plant"];
  plant_label.resize(field.positions().size());
  for (int plant = 0; plant < field.plant_count(); ++plant) {
    const auto [first, last] = field.node_range(plant);
    for (int node = first; node < last; ++node) {
      plant_label[node] = plant;
      if (node + 1 < last) frame.segments.push_back({node, node + 1});
    }
  }
  return frame;
}

// One row per interval: time, then one tip displacement per plant along a fixed direction
// (streamwise) or along each plant's own unstressed direction (height).
class TipSeries {
 public:
  TipSeries(const std::filesystem::path& path, int plants) : out_(path) {
    if (!out_) throw std::runtime_error("vegetation_beam: cannot write " + path.string());
    out_ << "time";
    for (int plant = 0; plant < plants; ++plant) out_ << ",plant_" << plant;
    out_ << '\n';
    out_.precision(9);
  }
  template <class Displacement>
  void write(const vegetation::PlantField& field, Displacement displacement) {
    out_ << field.time();
    for (int plant = 0; plant < field.plant_count(); ++plant) out_ << ',' << displacement(plant);
    out_ << '\n';
  }
  void flush() { out_.flush(); }

 private:
  std::ofstream out_;
};

double mean_after(const std::vector<double>& times, const std::vector<double>& values,
                  double from) {
  double sum = 0.0;
  int count = 0;
  for (std::size_t i = 0; i < times.size(); ++i) {
    if (times[i] >= from) {
      sum += values[i];
      ++count;
    }
  }
  return count > 0 ? sum / count : values.empty() ? 0.0 : values.back();
}

void report_metrics(const vegetation::VegetationConfig& config, const vegetation::PlantField& field,
                    const std::vector<double>& times, const std::vector<double>& tip_streamwise,
                    const std::vector<double>& tip_height, coupler::MetricsReport& report) {
  const int probe = config.elastica_reference ? config.elastica_reference->plant : 0;
  const auto& spec = field.specs()[probe];
  if (!config.elastica_reference) {
    report.value("tip_streamwise_position", tip_streamwise.empty() ? 0.0 : tip_streamwise.back(),
                 "m");
    report.value("tip_height", tip_height.empty() ? spec.length : tip_height.back(), "m");
    return;
  }
  const auto& reference = *config.elastica_reference;
  const auto& parameters = field.parameters();
  const Eigen::Vector3d up = spec.direction.normalized();
  const Eigen::Vector3d across = reference.velocity - reference.velocity.dot(up) * up;
  vegetation::ElasticaProblem problem;
  problem.length = spec.length;
  problem.bending_stiffness = spec.bending_stiffness;  // specs() hold the derived EI
  problem.width = spec.width;
  problem.thickness = spec.thickness;
  problem.plant_density = spec.density;
  problem.fluid_density = parameters.fluid_density;
  problem.drag_coefficient = parameters.drag_coefficient;
  problem.speed = across.norm();
  problem.gravity = -parameters.gravity.dot(up);
  const auto solution = vegetation::solve_elastica(problem);
  const double from = field.time() - reference.average_over;
  const std::string source =
      "steady elastica with normal drag and buoyancy (monotone equilibrium, shooting, 4000 steps)";
  report.compare("tip_streamwise_position", mean_after(times, tip_streamwise, from),
                 solution.tip_streamwise, "m", source);
  report.compare("tip_height", mean_after(times, tip_height, from), solution.tip_height, "m",
                 source);
}

}  // namespace

int main(int argc, char** argv) {
  return coupler::run_process(argc, argv, "vegetation_beam", [](coupler::ProcessContext& context) {
    auto section = context.section();
    const vegetation::VegetationConfig config = vegetation::parse_config(section, context.scene);
    vegetation::PlantField field(config.plants, config.parameters);
    context.declare_frame(3, 0.0, config.parameters.gravity);
    // Beam checks act before window 0: point loads, the static start, the pluck.
    const vegetation::StartReport start = vegetation::prepare_start(field, config.checks);
    const auto modes = vegetation::modal_frequencies(field, config.checks.modes);
    if (!modes.empty()) vegetation::write_modes(context.output_dir() / "modes.csv", modes);
    auto& participant = *context.participant;
    const auto node_count = static_cast<std::size_t>(field.node_count());
    coupler::SolidLink link(participant, context.scene, node_count);
    output::PointSeriesWriter writer(context.output_dir() / "plants", "vegetation_beam");
    spdlog::info("{} plants, {} nodes, stable sub-step {:.3g} s", field.plant_count(), node_count,
                 field.stable_substep());

    const int probe = config.elastica_reference ? config.elastica_reference->plant : 0;
    const Eigen::Vector3d up = field.specs()[probe].direction.normalized();
    Eigen::Vector3d streamwise = Eigen::Vector3d::UnitX();
    if (config.elastica_reference) {
      const Eigen::Vector3d across =
          config.elastica_reference->velocity - config.elastica_reference->velocity.dot(up) * up;
      if (across.norm() > 0) streamwise = across.normalized();
    }
    std::vector<double> times, tip_streamwise, tip_height;
    // Seed 000 section 4: density change psi in every frame, honami amplitude of every tip.
    std::vector<double> initial_density;
    vegetation::TipAmplitude amplitude(config.canopy ? field.plant_count() : 0);
    if (config.canopy) {
      initial_density =
          vegetation::vegetation_number_density(field.positions(), config.canopy->psi_radius);
    }
    auto frame_of = [&](const vegetation::PlantField& plants) {
      return config.canopy ? make_frame(plants, &initial_density, config.canopy->psi_radius)
                           : make_frame(plants);
    };
    std::optional<TipSeries> tips, tip_heights;
    double next_tip = 0.0;
    auto write_tips = [&] {
      if (!config.canopy || field.time() < next_tip - 1e-12 * std::max(1.0, next_tip)) return;
      tips->write(field, [&](int plant) {
        return field.tip_displacement(plant).dot(config.canopy->streamwise);
      });
      tip_heights->write(field, [&](int plant) {
        return field.tip_displacement(plant).dot(field.specs()[plant].direction);
      });
      // Multiples of the interval: no drift, and one row per window if windows are longer.
      const double interval = config.canopy->tip_interval;
      next_tip = interval * (std::floor(field.time() / interval + 1e-9) + 1.0);
    };
    if (config.canopy) {
      tips.emplace(context.output_dir() / "tips.csv", field.plant_count());
      tip_heights.emplace(context.output_dir() / "tip_heights.csv", field.plant_count());
    }
    auto observe_canopy = [&] {
      if (!config.canopy || field.time() < config.canopy->amplitude_from) return;
      for (int plant = 0; plant < field.plant_count(); ++plant) {
        amplitude.observe(plant, field.tip_displacement(plant).dot(config.canopy->streamwise));
      }
    };
    auto record_tip = [&] {
      const auto [first, last] = field.node_range(probe);
      const Eigen::Vector3d tip = field.positions()[last - 1] - field.positions()[first];
      times.push_back(field.time());
      tip_streamwise.push_back(tip.dot(streamwise));
      tip_height.push_back(tip.dot(up));
    };

    const std::vector<Eigen::Vector3d> no_drag(node_count, Eigen::Vector3d::Zero());
    std::vector<double> water(node_count, 1.0);
    double next_output = 0.0;
    int64_t node_substeps = 0;
    int most_substeps = 0, most_newton_iterations = 0, newton_restarts = 0, cutbacks = 0;
    // Impulse the fluid gave the plants; the last window's is handed over after the run ends.
    Eigen::Vector3d drag_impulse = Eigen::Vector3d::Zero(),
                    last_drag_impulse = Eigen::Vector3d::Zero();
    while (true) {
      const coupler::Window window = participant.next_window();
      context.maybe_inject_fault(window.index);
      if (window.finish) {
        if (writer.frame_count() == 0 || next_output <= field.time())
          writer.write_frame(frame_of(field));
        writer.write_series("tip_streamwise_position", times, tip_streamwise);
        writer.write_series("tip_height", times, tip_height);
        coupler::MetricsReport report;
        report_metrics(config, field, times, tip_streamwise, tip_height, report);
        if (!modes.empty()) {  // of the probe plant, about its start shape
          for (std::size_t mode = 0; mode < modes[probe].size(); ++mode)
            report.value("mode_" + std::to_string(mode + 1) + "_frequency", modes[probe][mode],
                         "Hz");
        }
        if (config.canopy) {
          tips->flush();
          tip_heights->flush();
          report.value("mean_tip_amplitude", amplitude.mean_amplitude(), "m");
          double displacement = 0.0;
          for (int plant = 0; plant < field.plant_count(); ++plant)
            displacement += field.tip_displacement(plant).dot(config.canopy->streamwise);
          report.value("mean_tip_displacement", displacement / field.plant_count(), "m");
          const auto psi = vegetation::vegetation_density_change(
              vegetation::vegetation_number_density(field.positions(), config.canopy->psi_radius),
              initial_density);
          report.value("psi_min", *std::min_element(psi.begin(), psi.end()), "");
          report.value("psi_max", *std::max_element(psi.begin(), psi.end()), "");
        }
        report.info()["plants"] = field.plant_count();
        report.info()["nodes"] = node_count;
        report.info()["node_substeps"] = node_substeps;
        report.info()["most_substeps_in_a_window"] = most_substeps;
        report.info()["stable_substep"] = field.stable_substep();
        report.info()["most_newton_iterations"] = most_newton_iterations;
        report.info()["newton_restarts"] = newton_restarts;
        report.info()["substep_cutbacks"] = cutbacks;
        report.info()["static_solve_iterations"] = start.static_iterations;
        report.info()["kinetic_energy"] = field.kinetic_energy();
        report.info()["drag_impulse"] = {drag_impulse.x(), drag_impulse.y(), drag_impulse.z()};
        report.info()["last_window_drag_impulse"] = {last_drag_impulse.x(), last_drag_impulse.y(),
                                                     last_drag_impulse.z()};
        report.info()["elastic_energy"] = field.elastic_energy();
        participant.finished(report.dump());
        return;
      }
      if (window.index == 0) {
        record_tip();
        write_tips();
        writer.write_frame(frame_of(field));
        next_output = config.output_interval;
        link.publish_state(field.positions(), field.velocities(), no_drag);
        participant.done(0);
        continue;
      }
      const auto [begin, end] = link.ambient(window);
      // Emergent parts of a plant (water fraction 0) take no drag and no buoyancy.
      for (std::size_t k = 0; k < node_count; ++k) {
        water[k] = 0.5 * (begin.water_fraction[k] + end.water_fraction[k]);
      }
      field.set_water_fraction(water);
      const auto step = field.advance(window.dt, begin.velocity, end.velocity);
      node_substeps += static_cast<int64_t>(step.substeps) * static_cast<int64_t>(node_count);
      most_substeps = std::max(most_substeps, step.substeps);
      most_newton_iterations = std::max(most_newton_iterations, step.max_newton_iterations);
      newton_restarts += step.newton_restarts;
      cutbacks += step.cutbacks;
      last_drag_impulse.setZero();
      for (const auto& drag : field.window_mean_drag()) last_drag_impulse += drag * window.dt;
      drag_impulse += last_drag_impulse;
      record_tip();
      observe_canopy();
      write_tips();
      if (field.time() >= next_output - 1e-12 * std::max(1.0, next_output)) {
        writer.write_frame(frame_of(field));
        next_output += config.output_interval;
      }
      link.publish_state(field.positions(), field.velocities(), field.window_mean_drag());
      participant.done(step.substeps);
    }
  });
}
