// The fluid_mps process: one MPS step per coupling window (more if the window exceeds the
// stable step). Each window it takes minus the solids' drag, advances, samples the flow at the
// solids' nodes, writes particle frames for ParaView, and reports errors against its reference.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>

#include "cosim/coupler/links.hpp"
#include "cosim/coupler/process_main.hpp"
#include "cosim/coupler/solver_loop.hpp"
#include "cosim/fluid_mps/checkpoint.hpp"
#include "cosim/fluid_mps/observers.hpp"
#include "cosim/fluid_mps/scenes.hpp"
#include "cosim/output/point_series.hpp"
#include "fishway_report.hpp"
#include "fluid_config.hpp"
#include "overfall_report.hpp"
#include "references.hpp"
#include "scene_3d.hpp"

namespace {

using namespace cosim;

mps::ParticleSet build_scene(mps::MpsParameters& parameters, mps::SceneSettings& scene) {
  if (parameters.dimension == 3) return mps::build_scene_3d(parameters, scene);  // scene_3d.hpp
  if (scene.kind == "dam_break") {
    return mps::dam_break(parameters, scene.column_width, scene.column_height, scene.tank_length,
                          scene.tank_height, scene.wall_layers, scene.dummy_layers);
  }
  if (scene.kind == "periodic_channel") {
    // Slope 0: the bed slope is already in the world's gravity.
    return mps::periodic_channel(parameters, scene.length, scene.depth, 0.0, scene.wall_layers,
                                 scene.dummy_layers);
  }
  if (scene.kind == "pool_fishway") {
    return mps::pool_fishway(parameters, scene.inflow, scene.fishway, scene.weirs,
                             scene.wall_layers, scene.dummy_layers);
  }
  if (scene.kind == "periodic_pool") {
    // A level pool at the weir head of the discharge it is to carry.
    const double fill = mps::periodic_pool_fill(scene, parameters.gravity.norm());
    return mps::periodic_pool(parameters, scene.fishway, fill, scene.weirs, scene.wall_layers,
                              scene.dummy_layers);
  }
  if (scene.kind == "open_channel") {
    return mps::open_channel(parameters, scene.inflow, scene.length, scene.depth,
                             scene.block_height, scene.block_columns, scene.pool_particles,
                             scene.wall_layers, scene.dummy_layers, 0.0, scene.outlet);
  }
  return mps::still_water_tank(parameters, scene.width, scene.depth, scene.tank_height,
                               scene.wall_layers, scene.dummy_layers);
}

// An output frame holds everything a restart needs: positions, velocities, pressures, kinds, in
// the world frame (a 2D fluid in the x-z plane), so ParaView shows it with the solids.
output::PointFrame make_frame(const mps::FluidSystem& system, const coupler::SolverFrame& world) {
  output::PointFrame frame;
  frame.time = system.time();
  frame.positions.reserve(system.positions().size());
  for (const auto& x : system.positions()) frame.positions.push_back(world.to_world(x));
  auto& velocity = frame.vectors["velocity"];
  velocity.reserve(system.velocities().size());
  for (const auto& u : system.velocities()) velocity.push_back(world.to_world(u));
  frame.scalars["pressure"] = system.pressures();
  frame.scalars["number_density"] = system.number_densities();
  auto& kinds = frame.labels["kind"];
  for (const auto kind : system.kinds()) kinds.push_back(static_cast<int>(kind));
  return frame;
}

mps::MpsState state_from_frame(const mps::RestartSettings& restart,
                               const coupler::SolverFrame& world) {
  const auto frame = output::read_point_frame(restart.file, restart.frame);
  mps::MpsState state;
  state.time = frame.time;
  for (const auto& x : frame.positions) state.positions.push_back(world.to_solver(x));
  auto require = [&](const auto& map, const char* name) -> const auto& {
    const auto found = map.find(name);
    if (found == map.end()) {
      throw std::runtime_error(fmt::format("{}: frame {} has no '{}' to restart from",
                                           restart.file.string(), restart.frame, name));
    }
    return found->second;
  };
  for (const auto& u : require(frame.vectors, "velocity")) {
    state.velocities.push_back(world.to_solver(u));
  }
  state.pressures = require(frame.scalars, "pressure");
  for (const int kind : require(frame.labels, "kind")) {
    state.kinds.push_back(static_cast<mps::ParticleKind>(kind));
  }
  return state;
}

// The MPS library as a participant: the window is the fluid step (split when it exceeds the
// stable step), the solids' reaction comes from the link, samples go back through it.
class FluidProcess final : public coupler::Solver {
 public:
  explicit FluidProcess(coupler::ProcessContext& context)
      : config_(parse(context)),
        system_(make_system(config_)),
        link_(*context.participant, context.scene, config_.frame),
        writer_(context.output_dir() / "particles", "fluid_mps"),
        output_dir_(context.output_dir()) {
    const auto& scene = config_.scene;
    if (scene.kind == "open_channel" || scene.kind == "pool_fishway") {
      open_boundaries_ = std::make_unique<mps::OpenBoundaries>(*system_, scene.inflow);
    }
    if (config_.reference && config_.reference->kind == "weirs") {
      const bool periodic = scene.kind == "periodic_pool";
      fishway_.emplace(scene.weirs, config_.parameters.particle_spacing,
                       config_.reference->average_from,
                       periodic ? scene.fill_discharge : scene.inflow.discharge, periodic);
    } else if (config_.reference && config_.reference->kind == "free_overfall") {
      overfall_.emplace(scene.length, scene.inflow.discharge, config_.reference->average_from,
                        *system_, *open_boundaries_);
    } else if (config_.reference) {
      // Gravity along the library's vertical: y of the 2D plane, z in 3D.
      const int dimension = config_.parameters.dimension;
      reference_.emplace(*config_.reference, -config_.parameters.gravity[dimension - 1], dimension,
                         0.5 * scene.tank_width);
    }
    if (config_.observation) {
      observation_.emplace(config_.observation->points, config_.observation->radius);
    }
    writer_.describe("velocity", {"m/s", "particle velocity (world frame)", ""});
    writer_.describe("pressure", {"Pa", "particle pressure", ""});
    writer_.describe(
        "number_density",
        {"1", "MPS particle number density at r* (NaN for dummies: not computed)", ""});
    writer_.describe("kind", {"1", "particle kind", "0 fluid, 1 wall, 2 dummy, 3 inactive"});
    spdlog::info("{} particles, l0 = {} m, stable dt {:.3g} s", system_->particle_count(),
                 config_.parameters.particle_spacing, system_->stable_dt());
  }

  double output_interval() const { return config_.output_interval; }
  double output_time() const override { return system_->time(); }
  void write_output() override { writer_.write_frame(make_frame(*system_, config_.frame)); }

  coupler::WindowResult initial_window(const coupler::Window& window) override {
    initial_momentum_ = system_->total_fluid_momentum();
    return advance(window);
  }

  coupler::WindowResult advance(const coupler::Window& window) override {
    const auto solids = link_.receive_solids(window, config_.displacement_radius > 0.0);
    for (const auto& solid : solids) {
      if (link_.resolves(solid.name)) place_blade(solid, window);
    }
    int window_steps = 0;
    if (window.dt > 0.0) window_steps = step_window(window, solids);
    if (observation_) observation_->record(*system_);
    if (reference_)
      reference_->observe(*system_, impulses_, observation_ ? &*observation_ : nullptr);
    if (fishway_) fishway_->observe(*system_, open_boundaries_.get());
    if (overfall_) overfall_->observe(*system_, *open_boundaries_);
    for (const auto& solid : solids) {
      const auto sampling = mps::StageClock::now();
      const auto velocity =
          system_->sample_velocity(solid.positions, config_.sample_radius, &water_);
      system_->sample_surface(solid.positions, config_.sample_radius, surface_);
      hook_seconds_ += mps::seconds_since(sampling);
      link_.publish_samples(solid.name, velocity, water_, surface_);
      if (link_.resolves(solid.name)) link_.publish_fluid_load(solid.name, blade_load(window));
    }
    return {window_steps, system_->stable_dt()};
  }

  void finish(coupler::MetricsReport& report) override {
    if (reference_) {
      reference_->report(report);
      for (const auto& s : reference_->series()) {
        writer_.write_series(
            s.name, s.times, s.values,
            {s.unit, s.description, s.reference_times, s.reference_values, s.source});
      }
    }
    if (fishway_) fishway_->report(report);
    if (overfall_) overfall_->report(report);
    if (observation_) observation_->write_csv((output_dir_ / "observation_points.csv").string());
    auto& info = report.info();
    if (open_boundaries_) {
      info["inflow_volume"] = open_boundaries_->inflow_volume();
      info["recycled_particles"] = open_boundaries_->recycled_total();
      info["final_inflow_velocity"] = open_boundaries_->velocity();
      info["final_measured_level"] = open_boundaries_->measured_level();
    }
    info["particles"] = system_->particle_count();
    if (std::isfinite(config_.scene.outlet_x)) info["outlet_particles"] = outlet_particles_;
    if (config_.displacement_radius > 0.0) {
      // Above kMaximumSolidFraction the fluid was given back some of the solids' volume.
      info["largest_solid_fraction"] = largest_solid_fraction_;
    }
    // Where this process's compute went (wall seconds of this run; not carried over a restart).
    const mps::StageSeconds& t = stage_seconds_;
    info["stage_seconds"] = {{"search", t.search},
                             {"explicit", t.explicit_part},
                             {"collision", t.collision},
                             {"density", t.density},
                             {"assembly", t.assembly},
                             {"pressure_setup", t.pressure_setup},
                             {"pressure_solve", t.pressure_solve},
                             {"correction", t.correction},
                             {"finish", t.finish},
                             {"coupling_hooks", hook_seconds_}};
    info["neighbour_searches"] = neighbour_searches_;  // this run's, as stage_seconds
    info["steps"] = steps_;
    info["mean_pcg_iterations"] = steps_ > 0 ? double(pcg_iterations_) / steps_ : 0.0;
    info["most_pcg_iterations"] = most_pcg_iterations_;
    // World impulses [N s]: handed over by the link, actually received by the fluid particles,
    // not deliverable (no fluid near a solid point; out of a 2D plane).
    auto json = [](const Eigen::Vector3d& v) {
      return nlohmann::json::array({v.x(), v.y(), v.z()});
    };
    info["booked_solid_reaction_impulse"] = json(link_.booked_impulse());
    info["solid_reaction_impulse"] = json(config_.frame.force_to_world(impulses_.solids));
    info["undelivered_solid_force_impulse"] = json(config_.frame.force_to_world(undelivered_));
    info["out_of_plane_solid_force_impulse"] = json(link_.out_of_plane_impulse());
    // Momentum budget of the fluid (closed domains): its momentum change against every source
    // (gravity, walls, pressure, collisions, solids), relative to the gravity and solid impulses.
    // Open boundaries add and remove particles, which the budget does not follow; a flume's
    // outlet books the momentum the leaving water carries off (step_window).
    const Eigen::Vector3d change = system_->total_fluid_momentum() - initial_momentum_;
    if (!open_boundaries_ && budget_scale_ > 0.0) {
      info["momentum_budget_residual"] = (change - budget_sources_).norm() / budget_scale_;
    }
    info["fluid_momentum_change"] = json(config_.frame.force_to_world(change));
    if (!blade_.empty()) {
      // coupling.resolved_plants: the impulse of the fluid's pressure on the plant [N s].
      info["resolved_plant_load_impulse"] = json(config_.frame.force_to_world(blade_impulse_));
      // The largest distance between a node where the plant ended a window and where the fluid
      // had moved its wall particle [m]: the explicit scheme's extrapolation (of order a dt^2),
      // within the tolerance for converged implicit windows.
      info["resolved_wall_gap"] = resolved_wall_gap_;
    }
  }

  // The fluid's state through the library, the link's and this process's running totals. The
  // observers' and references' time series start again at the restart (they cover what the
  // restarted run computed).
  void save_checkpoint(checkpoint::Writer& out) const override {
    mps::save_checkpoint(*system_, out);
    link_.save_checkpoint(out);
    out.value("fluid_process.steps", steps_);
    out.value("fluid_process.pcg_iterations", pcg_iterations_);
    out.value("fluid_process.most_pcg_iterations", most_pcg_iterations_);
    if (std::isfinite(config_.scene.outlet_x)) {
      out.value("fluid_process.outlet_particles", outlet_particles_);
    }
    out.value("fluid_process.undelivered", undelivered_);
    out.value("fluid_process.largest_solid_fraction", largest_solid_fraction_);
    out.value("fluid_process.impulses", impulses_);
    out.value("fluid_process.initial_momentum", initial_momentum_);
    out.value("fluid_process.budget_sources", budget_sources_);
    out.value("fluid_process.budget_scale", budget_scale_);
    if (open_boundaries_) out.value("fluid_process.open_boundaries", open_boundaries_->state());
    if (!blade_.empty()) {
      out.vector("fluid_process.blade_particles", blade_);
      out.value("fluid_process.blade_impulse", blade_impulse_);
      out.value("fluid_process.resolved_wall_gap", resolved_wall_gap_);
    }
  }
  void load_checkpoint(const checkpoint::Reader& in) override {
    auto state = mps::load_checkpoint(in);
    // A resolved plant's wall particles follow the scene's (a fresh process has none yet).
    std::vector<int> blade;
    if (link_.resolves("vegetation_beam")) blade = in.vector<int>("fluid_process.blade_particles");
    const std::size_t added = blade_.empty() ? blade.size() : 0;
    if (state.positions.size() != static_cast<std::size_t>(system_->particle_count()) + added) {
      in.fail("fluid.positions", fmt::format("holds {} particles where this scene has {}",
                                             state.positions.size(), system_->particle_count()));
    }
    system_ = std::make_unique<mps::FluidSystem>(config_.parameters, state);
    if (open_boundaries_) {
      // The block and the pool come from the restored particles, the control's state and the
      // totals from the checkpoint.
      open_boundaries_ = std::make_unique<mps::OpenBoundaries>(*system_, config_.scene.inflow);
      open_boundaries_->restore(in.value<mps::OpenBoundaryState>("fluid_process.open_boundaries"));
    }
    link_.load_checkpoint(in);
    steps_ = in.value<int64_t>("fluid_process.steps");
    pcg_iterations_ = in.value<int64_t>("fluid_process.pcg_iterations");
    most_pcg_iterations_ = in.value<int>("fluid_process.most_pcg_iterations");
    if (std::isfinite(config_.scene.outlet_x)) {
      outlet_particles_ = in.value<int64_t>("fluid_process.outlet_particles");
    }
    undelivered_ = in.value<Eigen::Vector3d>("fluid_process.undelivered");
    largest_solid_fraction_ = in.value<double>("fluid_process.largest_solid_fraction");
    impulses_ = in.value<mps::FluidImpulses>("fluid_process.impulses");
    initial_momentum_ = in.value<Eigen::Vector3d>("fluid_process.initial_momentum");
    budget_sources_ = in.value<Eigen::Vector3d>("fluid_process.budget_sources");
    budget_scale_ = in.value<double>("fluid_process.budget_scale");
    if (!blade.empty()) {
      blade_ = std::move(blade);
      blade_impulse_ = in.value<Eigen::Vector3d>("fluid_process.blade_impulse");
      resolved_wall_gap_ = in.value<double>("fluid_process.resolved_wall_gap");
    }
  }

 private:
  static mps::FluidConfig parse(coupler::ProcessContext& context) {
    auto section = context.section();
    mps::FluidConfig config = mps::parse_config(section, context.scene);
    context.declare_frame(config.parameters.dimension, config.span,
                          config.frame.to_world(config.parameters.gravity),
                          /*limits_window=*/true);  // its CFL and viscous limits
    return config;
  }

  static std::unique_ptr<mps::FluidSystem> make_system(mps::FluidConfig& config) {
    mps::ParticleSet particles = build_scene(config.parameters, config.scene);
    if (config.initial_state) {
      // periodic_pool from a chain's pool: its fluid with the walls just built (chain_state.hpp).
      const auto& kinds = config.initial_state->kinds;
      spdlog::info("periodic pool from a chain frame: {} fluid particles",
                   std::count(kinds.begin(), kinds.end(), mps::ParticleKind::fluid));
      return std::make_unique<mps::FluidSystem>(config.parameters, *config.initial_state);
    }
    if (!config.restart) {
      return std::make_unique<mps::FluidSystem>(config.parameters, std::move(particles));
    }
    auto system = std::make_unique<mps::FluidSystem>(
        config.parameters, state_from_frame(*config.restart, config.frame));
    spdlog::info("restarted from {} frame {} at t = {:.6g} s", config.restart->file.string(),
                 config.restart->frame, system->time());
    return system;
  }

  // coupling.resolved_plants: the plant stands in the fluid as one wall particle per node, put
  // each window at the start of the node's path (coupler::exchange::resolved_path) and moved
  // along it with its velocity, with thin partitions along its links
  // (FluidSystem::set_moving_walls). The particles are added to the fluid the first time the
  // plant is seen (window 0).
  void place_blade(const coupler::SolidForcing& solid, const coupler::Window& window) {
    const double l0 = config_.parameters.particle_spacing;
    if (config_.parameters.dimension != 2) {
      throw std::runtime_error("coupling.resolved_plants needs a 2D fluid_mps");
    }
    for (std::size_t k = 0; k + 1 < solid.positions.size(); ++k) {
      const double length = (solid.positions[k + 1] - solid.positions[k]).norm();
      // A link much longer than l0 leaves gaps the water flows through (a plant given too few
      // links, or one torn apart by a diverging coupling).
      if (length > 1.5 * l0) {
        throw std::runtime_error(fmt::format(
            "coupling.resolved_plants: link {} of '{}' is {:.4g} m long, more than 1.5 times the "
            "fluid's particle_spacing {:.4g} m: its wall particles would let the water through",
            k + 1, solid.name, length, l0));
      }
    }
    if (blade_.empty()) {
      mps::MpsState state = system_->save_state();
      // The water stands about l0 off the plate, as against any wall (0.9 l0: a lattice
      // column half a spacing off the plate goes, the next one, 1.5 l0 off, stays).
      const auto wall = mps::append_wall_particles(state, solid.positions, 0.9 * l0);
      blade_ = wall.particles;
      if (wall.cleared > 0) {
        spdlog::info("'{}' stands in water: {} fluid particles within 0.9 l0 of it taken out",
                     solid.name, wall.cleared);
      }
      system_ = std::make_unique<mps::FluidSystem>(config_.parameters, state);
      if (open_boundaries_) {
        open_boundaries_ = std::make_unique<mps::OpenBoundaries>(*system_, config_.scene.inflow);
      }
      spdlog::info("'{}' resolved by {} wall particles", solid.name, blade_.size());
    }
    if (blade_.size() != solid.positions.size()) {
      throw std::runtime_error(fmt::format("'{}' sent {} points where its wall has {}", solid.name,
                                           solid.positions.size(), blade_.size()));
    }
    if (window.iteration == 0 && window.index > 1) {
      // Where the fluid moved the wall to in the last window against where the plant ended it.
      for (std::size_t k = 0; k < blade_.size(); ++k) {
        resolved_wall_gap_ = std::max(
            resolved_wall_gap_, (system_->positions()[blade_[k]] - solid.path_start[k]).norm());
      }
    }
    std::vector<mps::PartitionSegment> segments;
    const auto& start = solid.path_start;
    for (std::size_t k = 0; k < blade_.size(); ++k) {
      system_->set_particle(blade_[k], mps::ParticleKind::wall, start[k], solid.path_velocity[k]);
      if (k > 0) segments.push_back({start[k - 1].head<2>(), start[k].head<2>(), true});
    }
    system_->set_moving_walls(blade_, std::move(segments));
    blade_window_impulse_.assign(blade_.size(), Eigen::Vector3d::Zero());
  }

  // The pressure load on each node of the blade [N per m of span] at the end of a fluid step
  // (mps::plate_pressure_loads at the wall particles' positions), summed over the window's
  // steps times their length.
  void add_blade_load(double dt) {
    std::vector<Eigen::Vector3d> nodes;
    for (const int i : blade_) nodes.push_back(system_->positions()[i]);
    const auto loads = mps::plate_pressure_loads(*system_, nodes, config_.sample_radius);
    for (std::size_t k = 0; k < loads.size(); ++k) blade_window_impulse_[k] += loads[k] * dt;
  }

  // The mean load of the window on each node [N per m of span]; zero in window 0.
  std::vector<Eigen::Vector3d> blade_load(const coupler::Window& window) {
    std::vector<Eigen::Vector3d> load(blade_.size(), Eigen::Vector3d::Zero());
    if (!(window.dt > 0.0)) return load;
    for (std::size_t k = 0; k < load.size(); ++k) {
      load[k] = blade_window_impulse_[k] / window.dt;
      blade_impulse_ += blade_window_impulse_[k];
    }
    return load;
  }

  // All solids' submerged volumes in one set (their points in solid order).
  void set_displaced_volumes(const std::vector<coupler::SolidForcing>& solids) {
    const double ramp = config_.displacement_ramp;
    const double share = ramp > 0.0 ? std::min(1.0, system_->time() / ramp) : 1.0;
    std::vector<Eigen::Vector3d> points;
    std::vector<double> volumes;
    for (const auto& solid : solids) {
      points.insert(points.end(), solid.positions.begin(), solid.positions.end());
      for (const double v : solid.volumes) volumes.push_back(share * v);
    }
    system_->set_solid_volumes(std::move(points), std::move(volumes), config_.displacement_radius);
  }

  // The solids' reaction (minus their drag, in the fluid's plane, per span width, rescaled to
  // this window by the link) acts in every fluid step of the window.
  int step_window(const coupler::Window& window, const std::vector<coupler::SolidForcing>& solids) {
    std::vector<std::pair<std::vector<Eigen::Vector3d>, std::vector<Eigen::Vector3d>>> forces;
    for (const auto& solid : solids) {
      // A resolved plant acts through its wall particles; it reports no drag to react to.
      if (!link_.resolves(solid.name)) forces.emplace_back(solid.positions, solid.reaction);
    }
    const auto forcing = mps::StageClock::now();
    const auto delivery = system_->set_point_forces(forces, config_.sample_radius);
    if (config_.displacement_radius > 0.0) set_displaced_volumes(solids);
    hook_seconds_ += mps::seconds_since(forcing);
    undelivered_ += delivery.undelivered_force * window.dt;
    const int pieces =
        std::max(1, static_cast<int>(std::ceil(window.dt / system_->stable_dt() - 1e-9)));
    for (int piece = 0; piece < pieces; ++piece) {
      const auto step = system_->step(window.dt / pieces);
      if (!blade_.empty()) add_blade_load(window.dt / pieces);
      largest_solid_fraction_ =
          std::max(largest_solid_fraction_, system_->largest_solid_fraction());
      impulses_.solids += step.external_impulse;
      budget_sources_ += step.body_impulse + step.wall_viscous_force * (window.dt / pieces) +
                         step.collision_impulse + step.pressure_impulse + step.external_impulse +
                         step.shifting_impulse;
      budget_scale_ += step.body_impulse.norm() + step.external_impulse.norm();
      impulses_.wall_viscous += step.wall_viscous_force * (window.dt / pieces);
      impulses_.wall_collision += step.wall_collision_impulse;
      impulses_.wall_pressure += step.wall_pressure_impulse;
      impulses_.fluid_pressure += step.pressure_impulse - step.wall_pressure_impulse;
      impulses_.shifting += step.shifting_impulse;
      if (open_boundaries_) open_boundaries_->update();
      if (std::isfinite(config_.scene.outlet_x)) {
        // The momentum the leaving water carries off is booked, so the budget still closes.
        const Eigen::Vector3d before = system_->total_fluid_momentum();
        const int left = mps::remove_fluid_beyond(*system_, config_.scene.outlet_x);
        if (left > 0) {
          outlet_particles_ += left;
          budget_sources_ += system_->total_fluid_momentum() - before;
        }
      }
      stage_seconds_ += step.stage_seconds;
      neighbour_searches_ += step.neighbour_searches;
      pcg_iterations_ += step.pcg_iterations;
      most_pcg_iterations_ = std::max(most_pcg_iterations_, step.pcg_iterations);
    }
    steps_ += pieces;
    return pieces;
  }

  mps::FluidConfig config_;
  std::unique_ptr<mps::FluidSystem> system_;
  mps::StageSeconds stage_seconds_;  // summed over the steps of this run
  double hook_seconds_ = 0.0;        // point forces, displaced volumes, sampling
  int64_t neighbour_searches_ = 0;   // pair lists built in this run's steps
  coupler::FlowLink link_;
  output::PointSeriesWriter writer_;
  std::filesystem::path output_dir_;
  std::unique_ptr<mps::OpenBoundaries> open_boundaries_;
  std::optional<mps::FishwayReport> fishway_;
  std::optional<mps::OverfallReport> overfall_;
  std::optional<mps::ObservationPoints> observation_;
  std::optional<mps::ReferenceTracker> reference_;
  int64_t steps_ = 0, pcg_iterations_ = 0;
  int most_pcg_iterations_ = 0;
  int64_t outlet_particles_ = 0;  // fluid particles that left through the flume's outlet
  Eigen::Vector3d undelivered_ = Eigen::Vector3d::Zero();
  double largest_solid_fraction_ = 0.0;  // over the run (displacement_radius > 0)
  mps::FluidImpulses impulses_;          // momentum the fluid received, by source
  Eigen::Vector3d initial_momentum_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d budget_sources_ = Eigen::Vector3d::Zero();
  double budget_scale_ = 0.0;
  std::vector<double> water_, surface_;
  std::vector<int> blade_;  // coupling.resolved_plants: the plant's wall particles, node order
  double resolved_wall_gap_ = 0.0;                     // [m], see finish()
  std::vector<Eigen::Vector3d> blade_window_impulse_;  // this window's, per node [N s/m]
  Eigen::Vector3d blade_impulse_ = Eigen::Vector3d::Zero();
};

}  // namespace

int main(int argc, char** argv) {
  return coupler::run_process(argc, argv, "fluid_mps", [](coupler::ProcessContext& context) {
    FluidProcess fluid(context);
    coupler::run_solver_loop(context, fluid, fluid.output_interval());
  });
}
