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
#include "cosim/coupler/solver_loop.hpp"
#include "cosim/output/point_series.hpp"
#include "cosim/vegetation_beam/canopy_metrics.hpp"
#include "cosim/vegetation_beam/checkpoint.hpp"
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

// The plant library as a participant: sub-cycles through each window with the ambient flow,
// returns positions, velocities and the window-mean drag, and follows the tips.
class VegetationProcess final : public coupler::Solver {
 public:
  explicit VegetationProcess(coupler::ProcessContext& context)
      : config_(parse(context)),
        field_(config_.plants, config_.parameters),
        start_(vegetation::prepare_start(field_, config_.checks)),  // loads, static start, pluck
        node_count_(static_cast<std::size_t>(field_.node_count())),
        link_(*context.participant, context.scene, node_count_),
        writer_(context.output_dir() / "plants", "vegetation_beam"),
        probe_(config_.elastica_reference ? config_.elastica_reference->plant : 0),
        amplitude_(config_.canopy ? field_.plant_count() : 0),
        water_(node_count_, 1.0),
        held_forces_(field_.external_forces()),
        resolved_(context.scene.coupling.interface.resolved_plants) {
    context.declare_frame(3, 0.0, config_.parameters.gravity);
    if (resolved_) spdlog::info("resolved in the fluid: drag and added mass are the fluid's load");
    modes_ = vegetation::modal_frequencies(field_, config_.checks.modes);
    if (!modes_.empty()) vegetation::write_modes(context.output_dir() / "modes.csv", modes_);
    spdlog::info("{} plants, {} nodes, stable sub-step {:.3g} s", field_.plant_count(), node_count_,
                 field_.stable_substep());
    up_ = field_.specs()[probe_].direction.normalized();
    if (config_.elastica_reference) {
      const Eigen::Vector3d& v = config_.elastica_reference->velocity;
      const Eigen::Vector3d across = v - v.dot(up_) * up_;
      if (across.norm() > 0) streamwise_ = across.normalized();
    }
    if (config_.canopy) {
      // Seed 000 section 4: density change psi in every frame, honami amplitude of every tip.
      initial_density_ =
          vegetation::vegetation_number_density(field_.positions(), config_.canopy->psi_radius);
      tips_.emplace(context.output_dir() / "tips.csv", field_.plant_count());
      tip_heights_.emplace(context.output_dir() / "tip_heights.csv", field_.plant_count());
    }
  }

  double output_interval() const { return config_.output_interval; }
  double output_time() const override { return field_.time(); }
  void write_output() override {
    writer_.write_frame(config_.canopy
                            ? make_frame(field_, &initial_density_, config_.canopy->psi_radius)
                            : make_frame(field_));
  }

  coupler::WindowResult initial_window(const coupler::Window&) override {
    record_tip();
    write_tips();
    const std::vector<Eigen::Vector3d> no_drag(node_count_, Eigen::Vector3d::Zero());
    link_.publish_state(field_.positions(), field_.velocities(), no_drag);
    return {};
  }

  coupler::WindowResult advance(const coupler::Window& window) override {
    const auto [begin, end] = link_.ambient(window);
    // Emergent parts of a plant (water fraction 0) take no drag and no buoyancy.
    for (std::size_t k = 0; k < node_count_; ++k) {
      water_[k] = 0.5 * (begin.water_fraction[k] + end.water_fraction[k]);
    }
    field_.set_water_fraction(water_);
    if (resolved_) apply_fluid_load(window, end.fluid_load);
    const std::vector<Eigen::Vector3d> start = field_.positions();
    const auto step = field_.advance(window.dt, begin.velocity, end.velocity);
    node_substeps_ += static_cast<int64_t>(step.substeps) * static_cast<int64_t>(node_count_);
    most_substeps_ = std::max(most_substeps_, step.substeps);
    most_newton_iterations_ = std::max(most_newton_iterations_, step.max_newton_iterations);
    newton_restarts_ += step.newton_restarts;
    cutbacks_ += step.cutbacks;
    factorizations_ += step.factorizations;
    most_plants_in_contact_ = std::max(most_plants_in_contact_, step.most_plants_in_contact);
    plant_by_plant_windows_ += step.plants_apart ? 1 : 0;
    last_drag_impulse_.setZero();
    for (const auto& drag : field_.window_mean_drag()) last_drag_impulse_ += drag * window.dt;
    drag_impulse_ += last_drag_impulse_;
    record_tip();
    observe_canopy();
    link_.publish_window_state(start, window.dt, field_.positions(), field_.velocities(),
                               field_.window_mean_drag());
    return {step.substeps, 0.0};
  }

  // tips.csv and tip_heights.csv get their row once the window is final (an implicit scheme
  // runs advance() once an iteration).
  void window_accepted() override { write_tips(); }

  void finish(coupler::MetricsReport& report) override {
    writer_.write_series("tip_streamwise_position", times_, tip_streamwise_);
    writer_.write_series("tip_height", times_, tip_height_);
    report_metrics(config_, field_, times_, tip_streamwise_, tip_height_, report);
    if (!modes_.empty()) {  // of the probe plant, about its start shape
      for (std::size_t mode = 0; mode < modes_[probe_].size(); ++mode)
        report.value("mode_" + std::to_string(mode + 1) + "_frequency", modes_[probe_][mode], "Hz");
    }
    if (config_.canopy) report_canopy(report);
    auto& info = report.info();
    info["plants"] = field_.plant_count();
    info["nodes"] = node_count_;
    info["node_substeps"] = node_substeps_;
    info["most_substeps_in_a_window"] = most_substeps_;
    info["stable_substep"] = field_.stable_substep();
    info["most_newton_iterations"] = most_newton_iterations_;
    info["newton_restarts"] = newton_restarts_;
    info["substep_cutbacks"] = cutbacks_;
    info["jacobian_factorizations"] = factorizations_;
    info["most_plants_in_contact"] = most_plants_in_contact_;
    info["plant_by_plant_windows"] = plant_by_plant_windows_;  // this run's
    info["static_solve_iterations"] = start_.static_iterations;
    info["kinetic_energy"] = field_.kinetic_energy();
    // Impulse the fluid gave the plants; the last window's reaches the fluid after the run.
    info["drag_impulse"] = {drag_impulse_.x(), drag_impulse_.y(), drag_impulse_.z()};
    info["last_window_drag_impulse"] = {last_drag_impulse_.x(), last_drag_impulse_.y(),
                                        last_drag_impulse_.z()};
    info["elastic_energy"] = field_.elastic_energy();
    if (resolved_) {
      info["fluid_load_impulse"] = {fluid_load_impulse_.x(), fluid_load_impulse_.y(),
                                    fluid_load_impulse_.z()};
    }
  }

  // The plants through the library, and this process's tip series and totals. The honami
  // amplitude tracker starts again at the restart.
  void save_checkpoint(checkpoint::Writer& out) const override {
    vegetation::save_checkpoint(field_, out);
    out.vector("vegetation_process.times", times_);
    out.vector("vegetation_process.tip_streamwise", tip_streamwise_);
    out.vector("vegetation_process.tip_height", tip_height_);
    out.vector("vegetation_process.water", water_);
    out.value("vegetation_process.next_tip", next_tip_);
    out.value("vegetation_process.node_substeps", node_substeps_);
    out.value("vegetation_process.jacobian_factorizations", factorizations_);
    const int counts[4] = {most_substeps_, most_newton_iterations_, newton_restarts_, cutbacks_};
    out.bytes("vegetation_process.counts", counts, sizeof(int), 4);
    out.value("vegetation_process.drag_impulse", drag_impulse_);
    out.value("vegetation_process.last_drag_impulse", last_drag_impulse_);
    if (resolved_) out.value("vegetation_process.fluid_load_impulse", fluid_load_impulse_);
  }
  void load_checkpoint(const checkpoint::Reader& in) override {
    vegetation::load_checkpoint(field_, in);
    times_ = in.vector<double>("vegetation_process.times");
    tip_streamwise_ = in.vector<double>("vegetation_process.tip_streamwise");
    tip_height_ = in.vector<double>("vegetation_process.tip_height");
    in.vector_into("vegetation_process.water", water_);
    next_tip_ = in.value<double>("vegetation_process.next_tip");
    node_substeps_ = in.value<int64_t>("vegetation_process.node_substeps");
    // Checkpoints written before the count was kept restart it from zero.
    factorizations_ = in.has("vegetation_process.jacobian_factorizations")
                          ? in.value<int64_t>("vegetation_process.jacobian_factorizations")
                          : 0;
    const auto counts = in.vector<int>("vegetation_process.counts");
    if (counts.size() != 4) in.fail("vegetation_process.counts", "must hold 4 counts");
    most_substeps_ = counts[0];
    most_newton_iterations_ = counts[1];
    newton_restarts_ = counts[2];
    cutbacks_ = counts[3];
    drag_impulse_ = in.value<Eigen::Vector3d>("vegetation_process.drag_impulse");
    last_drag_impulse_ = in.value<Eigen::Vector3d>("vegetation_process.last_drag_impulse");
    if (resolved_) {
      fluid_load_impulse_ = in.value<Eigen::Vector3d>("vegetation_process.fluid_load_impulse");
    }
  }

 private:
  static vegetation::VegetationConfig parse(coupler::ProcessContext& context) {
    auto section = context.section();
    return vegetation::parse_config(section, context.scene);
  }

  // coupling.resolved_plants: the fluid's pressure force on the nodes over this window, held
  // constant through the window's sub-steps, on top of the scene's own loads.
  void apply_fluid_load(const coupler::Window& window, const std::vector<Eigen::Vector3d>& load) {
    std::vector<Eigen::Vector3d> forces = held_forces_;
    for (std::size_t k = 0; k < node_count_; ++k) {
      if (!load[k].allFinite()) {
        throw vegetation::StabilityError(fmt::format(
            "vegetation_beam: node {}: the fluid load from the fluid is not finite in window {}", k,
            window.index));
      }
      forces[k] += load[k];
      fluid_load_impulse_ += load[k] * window.dt;
    }
    field_.set_external_forces(std::move(forces));
  }

  void record_tip() {
    const auto [first, last] = field_.node_range(probe_);
    const Eigen::Vector3d tip = field_.positions()[last - 1] - field_.positions()[first];
    times_.push_back(field_.time());
    tip_streamwise_.push_back(tip.dot(streamwise_));
    tip_height_.push_back(tip.dot(up_));
  }

  void write_tips() {
    if (!config_.canopy || field_.time() < next_tip_ - 1e-12 * std::max(1.0, next_tip_)) return;
    const Eigen::Vector3d& streamwise = config_.canopy->streamwise;
    tips_->write(field_, [&](int plant) { return field_.tip_displacement(plant).dot(streamwise); });
    tip_heights_->write(field_, [&](int plant) {
      return field_.tip_displacement(plant).dot(field_.specs()[plant].direction);
    });
    // Multiples of the interval: no drift, and one row per window if windows are longer.
    const double interval = config_.canopy->tip_interval;
    next_tip_ = interval * (std::floor(field_.time() / interval + 1e-9) + 1.0);
  }

  void observe_canopy() {
    if (!config_.canopy || field_.time() < config_.canopy->amplitude_from) return;
    for (int plant = 0; plant < field_.plant_count(); ++plant) {
      amplitude_.observe(plant, field_.tip_displacement(plant).dot(config_.canopy->streamwise));
    }
  }

  void report_canopy(coupler::MetricsReport& report) {
    tips_->flush();
    tip_heights_->flush();
    report.value("mean_tip_amplitude", amplitude_.mean_amplitude(), "m");
    double displacement = 0.0;
    for (int plant = 0; plant < field_.plant_count(); ++plant)
      displacement += field_.tip_displacement(plant).dot(config_.canopy->streamwise);
    report.value("mean_tip_displacement", displacement / field_.plant_count(), "m");
    const auto psi = vegetation::vegetation_density_change(
        vegetation::vegetation_number_density(field_.positions(), config_.canopy->psi_radius),
        initial_density_);
    report.value("psi_min", *std::min_element(psi.begin(), psi.end()), "");
    report.value("psi_max", *std::max_element(psi.begin(), psi.end()), "");
  }

  const vegetation::VegetationConfig config_;
  vegetation::PlantField field_;
  const vegetation::StartReport start_;
  std::vector<std::vector<double>> modes_;
  const std::size_t node_count_;
  coupler::SolidLink link_;
  output::PointSeriesWriter writer_;
  const int probe_;
  Eigen::Vector3d up_ = Eigen::Vector3d::UnitZ(), streamwise_ = Eigen::Vector3d::UnitX();
  std::vector<double> times_, tip_streamwise_, tip_height_;
  std::vector<double> initial_density_;
  vegetation::TipAmplitude amplitude_;
  std::optional<TipSeries> tips_, tip_heights_;
  double next_tip_ = 0.0;
  std::vector<double> water_;
  int64_t node_substeps_ = 0;
  int most_substeps_ = 0, most_newton_iterations_ = 0, newton_restarts_ = 0, cutbacks_ = 0;
  int64_t factorizations_ = 0;      // plant Jacobians factorised over the run
  int most_plants_in_contact_ = 0;  // since the start or the restart
  // Windows solved plant by plant (no two plants could touch), in this run.
  int64_t plant_by_plant_windows_ = 0;
  Eigen::Vector3d drag_impulse_ = Eigen::Vector3d::Zero(),
                  last_drag_impulse_ = Eigen::Vector3d::Zero();
  const std::vector<Eigen::Vector3d> held_forces_;  // the scene's loads after the start
  const bool resolved_;
  Eigen::Vector3d fluid_load_impulse_ = Eigen::Vector3d::Zero();
};

}  // namespace

int main(int argc, char** argv) {
  return coupler::run_process(argc, argv, "vegetation_beam", [](coupler::ProcessContext& context) {
    VegetationProcess plants(context);
    coupler::run_solver_loop(context, plants, plants.output_interval());
  });
}
