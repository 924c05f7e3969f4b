// The debris_dem process: builds the structure (seed 004 flume, dam and gated debris packing,
// and/or an open box) and the explicit elements, lets a gated packing settle, then (gate removed
// at t = 0) sub-cycles through every coupling window with the ambient flow at its moving
// elements, returning positions, velocities and fluid forces. Reports the capture rate P_V of
// seed 004 eq. 55 and the woody-debris ratio K_w of eq. 54 when there is a dam (and, with
// front_gauge_x, the debris flow's length and shape as its front passes that x), the
// volume-weighted mean velocity, and a single element's final state.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <string>

#include "cosim/coupler/links.hpp"
#include "cosim/coupler/metrics.hpp"
#include "cosim/coupler/process_main.hpp"
#include "cosim/coupler/solver_loop.hpp"
#include "cosim/debris_dem/checkpoint.hpp"
#include "cosim/output/point_series.hpp"
#include "debris_scene.hpp"
#include "dem_config.hpp"

namespace {

using namespace cosim;

// The flow over window [begin, end] as the DEM holds it across its sub-steps: mean velocity,
// water fraction and surface, and the change of the sampled velocity over the window as Du/Dt
// (the samples follow the elements, so this is d/dt along the element path, which is Du/Dt
// where the element moves with the fluid).
dem::FluidAtElements window_fluid(const coupler::AmbientFlow& begin,
                                  const coupler::AmbientFlow& end, double dt) {
  dem::FluidAtElements fluid;
  const std::size_t n = begin.velocity.size();
  fluid.velocity.resize(n);
  fluid.acceleration.resize(n);
  fluid.water_fraction.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    fluid.velocity[i] = 0.5 * (begin.velocity[i] + end.velocity[i]);
    fluid.acceleration[i] = (end.velocity[i] - begin.velocity[i]) / dt;
    fluid.water_fraction[i] = 0.5 * (begin.water_fraction[i] + end.water_fraction[i]);
  }
  if (begin.surface_elevation.size() == n && end.surface_elevation.size() == n) {
    fluid.surface_elevation.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      // NaN (unknown) stays NaN; -inf (no water above) stays -inf.
      fluid.surface_elevation[i] = 0.5 * (begin.surface_elevation[i] + end.surface_elevation[i]);
    }
  }
  return fluid;
}

Eigen::Vector3d mean_velocity(const dem::DemWorld& world) {
  Eigen::Vector3d momentum = Eigen::Vector3d::Zero();
  double volume = 0.0;
  for (const int i : world.moving_elements()) {
    momentum += world.volume(i) * world.velocity(i);
    volume += world.volume(i);
  }
  return volume > 0.0 ? Eigen::Vector3d(momentum / volume) : Eigen::Vector3d::Zero();
}

// Per-window time series of the mean velocity and of each explicit element's position and
// velocity, stored under /series in the debris HDF5 file at the end of the run (a rewrite
// replaces the datasets, and HDF5 does not reclaim the old ones' space).
class Series {
 public:
  explicit Series(std::vector<int> elements) : elements_(std::move(elements)) {
    values_.resize(3 + 6 * elements_.size());
  }
  void record(double time, const dem::DemWorld& world) {
    times_.push_back(time);
    const Eigen::Vector3d mean = mean_velocity(world);
    for (int c = 0; c < 3; ++c) values_[c].push_back(mean[c]);
    for (std::size_t e = 0; e < elements_.size(); ++e) {
      for (int c = 0; c < 3; ++c) {
        values_[3 + 6 * e + c].push_back(world.position(elements_[e])[c]);
        values_[6 + 6 * e + c].push_back(world.velocity(elements_[e])[c]);
      }
    }
  }
  void save(checkpoint::Writer& out) const {
    out.vector("debris_process.series_times", times_);
    for (std::size_t k = 0; k < values_.size(); ++k) {
      out.vector("debris_process.series_" + std::to_string(k), values_[k]);
    }
  }
  void load(const checkpoint::Reader& in) {
    times_ = in.vector<double>("debris_process.series_times");
    for (std::size_t k = 0; k < values_.size(); ++k) {
      values_[k] = in.vector<double>("debris_process.series_" + std::to_string(k));
    }
  }
  void write(output::PointSeriesWriter& writer) const {
    static constexpr std::array<const char*, 3> kAxes{"x", "y", "z"};
    for (int c = 0; c < 3; ++c) {
      writer.write_series(std::string("mean_velocity_") + kAxes[c], times_, values_[c]);
    }
    for (std::size_t e = 0; e < elements_.size(); ++e) {
      const std::string name = "element_" + std::to_string(e) + "_";
      for (int c = 0; c < 3; ++c) {
        writer.write_series(name + kAxes[c], times_, values_[3 + 6 * e + c]);
        writer.write_series(name + "velocity_" + kAxes[c], times_, values_[6 + 6 * e + c]);
      }
    }
  }

 private:
  std::vector<int> elements_;
  std::vector<double> times_;
  std::vector<std::vector<double>> values_;
};

struct RunTotals {
  int64_t element_substeps = 0;
  double largest_overlap = 0.0;
  Eigen::Vector3d fluid_impulse = Eigen::Vector3d::Zero();
  Eigen::Vector3d last_fluid_impulse = Eigen::Vector3d::Zero();  // interaction, last window
  Eigen::Vector3d interaction_impulse = Eigen::Vector3d::Zero();
};

// The debris flow's shape when its front first passed front_gauge_x (dem::DebrisFront).
struct FrontRecord {
  bool taken = false;
  double time = 0.0;  // after the gate opened [s]
  dem::DebrisFront front;

  void observe(double now, const dem::DemWorld& world, const std::vector<int>& debris,
               const dem::DebrisConfig& config) {
    if (taken || !config.front_gauge_x) return;
    const double width = config.flume ? config.flume->width : 1.0;
    dem::DebrisFront f = dem::debris_front(world, debris, width);
    if (f.front < *config.front_gauge_x) return;
    taken = true;
    time = now;
    front = std::move(f);
  }
  void report(coupler::MetricsReport& report) const {
    const double nan = std::nan("");
    report.value("debris_front_length", taken ? front.length : nan, "m");
    report.value("debris_front_time", taken ? time : nan, "s");
    report.value("debris_front_extent", taken ? front.extent : nan, "m");
    report.value("debris_head_over_body", taken ? front.head_over_body : nan, "");
    report.value("debris_log_front_enrichment", taken ? front.log_front_enrichment : nan, "");
    if (!taken) return;
    report.info()["front_profile_x"] = front.bin_x;
    report.info()["front_profile_top"] = front.top;
    report.info()["front_profile_solid_depth"] = front.solid_depth;
    report.info()["front_position"] = front.front;
    report.info()["front_tail"] = front.tail;
  }
  void save(checkpoint::Writer& out) const {
    out.vector("debris_process.front_scalars",
               std::vector<double>{taken ? 1.0 : 0.0, time, front.front, front.tail, front.length,
                                   front.extent, front.head_over_body, front.log_front_enrichment});
    out.vector("debris_process.front_x", front.bin_x);
    out.vector("debris_process.front_top", front.top);
    out.vector("debris_process.front_solid_depth", front.solid_depth);
  }
  void load(const checkpoint::Reader& in) {
    const auto v = in.vector<double>("debris_process.front_scalars");
    taken = v.at(0) != 0.0;
    time = v.at(1);
    front.front = v.at(2);
    front.tail = v.at(3);
    front.length = v.at(4);
    front.extent = v.at(5);
    front.head_over_body = v.at(6);
    front.log_front_enrichment = v.at(7);
    front.bin_x = in.vector<double>("debris_process.front_x");
    front.top = in.vector<double>("debris_process.front_top");
    front.solid_depth = in.vector<double>("debris_process.front_solid_depth");
  }
};

void finish_report(const dem::DemWorld& world, const dem::DebrisConfig& config,
                   const dem::BuiltScene& scene, const RunTotals& totals,
                   coupler::MetricsReport& report) {
  const std::vector<int>& moving = world.moving_elements();
  if (config.dam) {
    report.value("capture_rate_P_V", dem::capture_rate(world, moving, config.dam->x), "");
    // P_V counts everything upstream of the dam, so it only means capture once the debris has
    // arrived: the volume fraction within 0.2 m of the dam or past it.
    double arrived = 0.0, total = 0.0;
    for (const int element : moving) {
      total += world.volume(element);
      if (world.position(element).x() > config.dam->x - 0.2) arrived += world.volume(element);
    }
    report.value("debris_arrived_at_dam", total > 0 ? arrived / total : 0.0, "");
    double d_max = 0.0;
    for (const auto& sphere_class : config.sphere_classes) {
      d_max = std::max(d_max, sphere_class.diameter);
    }
    for (const auto& e : config.elements) d_max = std::max(d_max, e.is_log() ? 0.0 : e.diameter);
    report.value("gap_ratio_lV_over_dmax", config.dam->vertical_gap / d_max, "");
  }
  report.value("woody_debris_ratio_K_w",
               scene.log_volume / (scene.sphere_volume + scene.log_volume), "");
  const Eigen::Vector3d mean = mean_velocity(world);
  report.value("mean_velocity_x", mean.x(), "m/s");
  report.value("mean_velocity_y", mean.y(), "m/s");
  report.value("mean_velocity_z", mean.z(), "m/s");
  report.info()["mean_velocity"] = {mean.x(), mean.y(), mean.z()};
  if (moving.size() == 1) {
    const Eigen::Vector3d v = world.velocity(moving[0]);
    report.value("element_final_z", world.position(moving[0]).z(), "m");
    report.value("element_final_velocity_x", v.x(), "m/s");
    report.value("element_final_velocity_y", v.y(), "m/s");
    report.value("element_final_velocity_z", v.z(), "m/s");
  }
  report.info()["spheres"] = scene.packing.spheres.size();
  report.info()["logs"] = scene.packing.logs.size();
  report.info()["explicit_elements"] = scene.explicit_elements.size();
  report.info()["element_substeps"] = totals.element_substeps;
  report.info()["settle_wall_seconds"] = scene.settle_seconds;
  report.info()["largest_overlap_ratio"] = totals.largest_overlap;
  report.info()["list_rebuilds"] = world.list_rebuilds();
  // Impulse the fluid gave the elements; the last window's reaches the fluid after the run.
  report.info()["fluid_impulse"] = {totals.fluid_impulse.x(), totals.fluid_impulse.y(),
                                    totals.fluid_impulse.z()};
  // The drag and added-mass part, which the fluid takes back (one window later).
  const auto& taken = totals.interaction_impulse;
  const auto& last = totals.last_fluid_impulse;
  report.info()["interaction_impulse"] = {taken.x(), taken.y(), taken.z()};
  report.info()["last_window_interaction_impulse"] = {last.x(), last.y(), last.z()};
}

// The DEM library as a participant: sub-cycles each window in the ambient flow at its moving
// elements and returns their positions, velocities and the window-mean fluid force.
class DebrisProcess final : public coupler::Solver {
 public:
  explicit DebrisProcess(coupler::ProcessContext& context)
      : config_(parse(context)),
        world_(config_.parameters),
        scene_(dem::build_scene(world_, config_)),
        debris_(world_.moving_elements()),
        link_(*context.participant, context.scene, debris_.size()),
        writer_(context.output_dir() / "debris", "debris_dem"),
        series_(scene_.explicit_elements),
        time_offset_(world_.time()) {  // the settling behind a gate comes before the run
    // The gravity the DEM really uses, so the coupler refuses a scene that differs.
    context.declare_frame(3, 0.0, config_.parameters.gravity);
    dem::write_structure(world_, context.output_dir() / "structure");
    if (config_.reference && config_.reference->kind == dem::ReferenceKind::hindered) {
      const auto& p = config_.parameters;
      const auto& packing = *config_.packing;
      const double d = config_.sphere_classes.front().diameter;
      const double rho_s = config_.debris.density;
      const double v_t = dem::schiller_naumann_terminal_velocity(
          d, rho_s, p.fluid_density, p.fluid_viscosity, p.gravity.norm());
      const double phi = scene_.sphere_volume / (packing.box_max - packing.box_min).prod();
      suspension_.emplace(config_.reference->average_from, phi, v_t,
                          p.fluid_density * v_t * d / p.fluid_viscosity);
    } else if (config_.reference) {
      const auto& e = config_.elements.front();
      const auto& p = config_.parameters;
      const double ratio = e.material.density / p.fluid_density;
      double value = 0.0;
      if (config_.reference->kind == dem::ReferenceKind::settling) {
        value = dem::schiller_naumann_terminal_velocity(
            e.diameter, e.material.density, p.fluid_density, p.fluid_viscosity, p.gravity.norm());
      } else {
        value = e.is_log() ? dem::floating_cylinder_draft(e.diameter, ratio)
                           : dem::floating_sphere_draft(e.diameter, ratio);
      }
      reference_.emplace(*config_.reference, value, 0.5 * e.diameter);
    }
  }

  double output_interval() const { return config_.output_interval; }
  double output_time() const override { return world_.time() - time_offset_; }
  void write_output() override { writer_.write_frame(dem::make_frame(world_, debris_)); }

  coupler::WindowResult initial_window(const coupler::Window&) override {
    series_.record(0.0, world_);
    const std::vector<Eigen::Vector3d> no_force(debris_.size(), Eigen::Vector3d::Zero());
    link_.publish_state(world_.element_centers(), world_.element_velocities(), no_force,
                        submerged_volumes());
    return {};
  }

  coupler::WindowResult advance(const coupler::Window& window) override {
    const auto [begin, end] = link_.ambient(window);
    const dem::FluidAtElements fluid = window_fluid(begin, end, window.dt);
    const auto step = world_.advance(window.dt, fluid);
    totals_.element_substeps +=
        static_cast<int64_t>(step.substeps) * static_cast<int64_t>(debris_.size());
    totals_.largest_overlap = std::max(totals_.largest_overlap, step.max_overlap_ratio);
    for (const auto& f : world_.window_mean_fluid_force()) totals_.fluid_impulse += f * window.dt;
    totals_.last_fluid_impulse.setZero();
    for (const auto& f : world_.window_mean_interaction_force()) {
      totals_.last_fluid_impulse += f * window.dt;
    }
    totals_.interaction_impulse += totals_.last_fluid_impulse;
    series_.record(output_time(), world_);
    front_.observe(output_time(), world_, debris_, config_);
    if (suspension_) suspension_->observe(output_time(), mean_velocity(world_));
    if (reference_) {
      const int element = debris_.front();
      const double surface =
          fluid.surface_elevation.empty() ? std::nan("") : fluid.surface_elevation.front();
      reference_->observe(output_time(), world_.position(element), world_.velocity(element),
                          surface);
    }
    // The fluid takes back the interaction force (drag, added mass), not the buoyancy its own
    // pressure already carries (DemWorld::window_mean_interaction_force).
    link_.publish_state(world_.element_centers(), world_.element_velocities(),
                        world_.window_mean_interaction_force(), submerged_volumes());
    return {step.substeps, 0.0};
  }

  void finish(coupler::MetricsReport& report) override {
    series_.write(writer_);
    finish_report(world_, config_, scene_, totals_, report);
    if (config_.front_gauge_x) front_.report(report);
    if (reference_) reference_->report(report);
    if (suspension_) suspension_->report(report);
  }

  // The elements through the library, and this process's series and totals. The settling
  // behind a gate is redone when the scene is built (it comes before t = 0); the references'
  // observations start again at the restart.
  void save_checkpoint(checkpoint::Writer& out) const override {
    dem::save_checkpoint(world_, out);
    series_.save(out);
    out.value("debris_process.totals", totals_);
    front_.save(out);
  }
  void load_checkpoint(const checkpoint::Reader& in) override {
    dem::load_checkpoint(world_, in);
    series_.load(in);
    totals_ = in.value<RunTotals>("debris_process.totals");
    front_.load(in);
  }

 private:
  // Water each moving element displaces [m^3]: its submerged share of its volume.
  std::vector<double> submerged_volumes() const {
    std::vector<double> volumes;
    volumes.reserve(debris_.size());
    const auto& fraction = world_.submerged_fraction();
    for (std::size_t k = 0; k < debris_.size(); ++k) {
      volumes.push_back(fraction[k] * world_.volume(debris_[k]));
    }
    return volumes;
  }

  static dem::DebrisConfig parse(coupler::ProcessContext& context) {
    auto section = context.section();
    return dem::parse_config(section, context.scene);
  }

  const dem::DebrisConfig config_;
  dem::DemWorld world_;
  const dem::BuiltScene scene_;
  const std::vector<int> debris_;
  coupler::SolidLink link_;
  output::PointSeriesWriter writer_;
  Series series_;
  const double time_offset_;
  RunTotals totals_;
  FrontRecord front_;
  std::optional<dem::ElementReference> reference_;
  std::optional<dem::SuspensionReference> suspension_;
};

}  // namespace

int main(int argc, char** argv) {
  return coupler::run_process(argc, argv, "debris_dem", [](coupler::ProcessContext& context) {
    DebrisProcess debris(context);
    coupler::run_solver_loop(context, debris, debris.output_interval());
  });
}
