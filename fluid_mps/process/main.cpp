// The fluid_mps process: one MPS step per coupling window (more if the window exceeds the
// stable step). Each window it takes minus the solids' drag, advances, samples the flow at the
// solids' nodes, writes particle frames for ParaView, and reports errors against its reference.
#include <spdlog/spdlog.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "cosim/coupler/links.hpp"
#include "cosim/coupler/process_main.hpp"
#include "cosim/fluid_mps/observers.hpp"
#include "cosim/fluid_mps/scenes.hpp"
#include "cosim/output/point_series.hpp"
#include "fishway_report.hpp"
#include "fluid_config.hpp"
#include "references.hpp"

namespace {

using namespace cosim;

mps::ParticleSet build_scene(mps::MpsParameters& parameters, mps::SceneSettings& scene) {
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
    const auto& g = scene.fishway;
    const double fill = g.weir_height + mps::rehbock_head(scene.fill_discharge, g.weir_height,
                                                          parameters.gravity.norm());
    return mps::periodic_pool(parameters, scene.fishway, fill, scene.weirs, scene.wall_layers,
                              scene.dummy_layers);
  }
  if (scene.kind == "open_channel") {
    return mps::open_channel(parameters, scene.inflow, scene.length, scene.depth,
                             scene.block_height, scene.block_columns, scene.pool_particles,
                             scene.wall_layers, scene.dummy_layers, 0.0);
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

}  // namespace

int main(int argc, char** argv) {
  return coupler::run_process(argc, argv, "fluid_mps", [](coupler::ProcessContext& context) {
    auto section = context.section();
    mps::FluidConfig config = mps::parse_config(section, context.scene);
    context.declare_frame(config.parameters.dimension, config.span,
                          config.frame.to_world(config.parameters.gravity));
    mps::ParticleSet particles = build_scene(config.parameters, config.scene);
    std::unique_ptr<mps::FluidSystem> system;
    std::unique_ptr<mps::OpenBoundaries> open_boundaries;
    if (config.restart) {
      system = std::make_unique<mps::FluidSystem>(config.parameters,
                                                  state_from_frame(*config.restart, config.frame));
      spdlog::info("restarted from {} frame {} at t = {:.6g} s", config.restart->file.string(),
                   config.restart->frame, system->time());
    } else {
      system = std::make_unique<mps::FluidSystem>(config.parameters, std::move(particles));
    }
    if (config.scene.kind == "open_channel" || config.scene.kind == "pool_fishway") {
      open_boundaries = std::make_unique<mps::OpenBoundaries>(*system, config.scene.inflow);
    }
    std::optional<mps::FishwayReport> fishway;
    if (config.reference && config.reference->kind == "weirs") {
      const bool periodic = config.scene.kind == "periodic_pool";
      fishway.emplace(
          config.scene.weirs, config.parameters.particle_spacing, config.reference->average_from,
          periodic ? config.scene.fill_discharge : config.scene.inflow.discharge, periodic);
    }
    std::optional<mps::ObservationPoints> observation;
    if (config.observation) {
      observation.emplace(config.observation->points, config.observation->radius);
    }
    spdlog::info("{} particles, l0 = {} m, stable dt {:.3g} s", system->particle_count(),
                 config.parameters.particle_spacing, system->stable_dt());

    auto& participant = *context.participant;
    coupler::FlowLink link(participant, context.scene, config.frame);
    output::PointSeriesWriter writer(context.output_dir() / "particles", "fluid_mps");
    std::optional<mps::ReferenceTracker> reference;
    if (config.reference && !fishway) {
      reference.emplace(*config.reference, -config.parameters.gravity.y());
    }

    double next_output = system->time();
    int64_t steps = 0, pcg_iterations = 0;
    int most_pcg_iterations = 0;
    Eigen::Vector3d undelivered = Eigen::Vector3d::Zero();
    mps::FluidImpulses impulses;  // momentum the fluid received, by source
    std::vector<double> water, surface;
    while (true) {
      const coupler::Window window = participant.next_window();
      context.maybe_inject_fault(window.index);
      if (window.finish) {
        if (system->time() > next_output - config.output_interval * 0.5)
          writer.write_frame(make_frame(*system, config.frame));
        coupler::MetricsReport report;
        if (reference) reference->report(report);
        if (fishway) fishway->report(report);
        if (observation)
          observation->write_csv((context.output_dir() / "observation_points.csv").string());
        if (open_boundaries) {
          report.info()["inflow_volume"] = open_boundaries->inflow_volume();
          report.info()["recycled_particles"] = open_boundaries->recycled_total();
          report.info()["final_inflow_velocity"] = open_boundaries->velocity();
          report.info()["final_measured_level"] = open_boundaries->measured_level();
        }
        report.info()["particles"] = system->particle_count();
        report.info()["steps"] = steps;
        report.info()["mean_pcg_iterations"] = steps > 0 ? double(pcg_iterations) / steps : 0.0;
        report.info()["most_pcg_iterations"] = most_pcg_iterations;
        // World impulses [N s]: handed over by the link, actually received by the fluid
        // particles, not deliverable (no fluid near a solid point; out of a 2D plane).
        auto world_impulse = [&](const Eigen::Vector3d& solver_impulse) {
          const Eigen::Vector3d w = config.frame.force_to_world(solver_impulse);
          return nlohmann::json::array({w.x(), w.y(), w.z()});
        };
        const auto& booked = link.booked_impulse();
        const auto& out_of_plane = link.out_of_plane_impulse();
        report.info()["booked_solid_reaction_impulse"] = {booked.x(), booked.y(), booked.z()};
        report.info()["solid_reaction_impulse"] = world_impulse(impulses.solids);
        report.info()["undelivered_solid_force_impulse"] = world_impulse(undelivered);
        report.info()["out_of_plane_solid_force_impulse"] = {out_of_plane.x(), out_of_plane.y(),
                                                             out_of_plane.z()};
        participant.finished(report.dump());
        return;
      }
      auto solids = link.receive_solids(window);
      int window_steps = 0;
      if (window.dt > 0.0) {
        // The link hands over minus the solids' drag of the previous window, in the fluid's
        // plane and per span width, rescaled to this window; it acts in every step of it.
        std::vector<std::pair<std::vector<Eigen::Vector3d>, std::vector<Eigen::Vector3d>>> forces;
        for (const auto& solid : solids) forces.emplace_back(solid.positions, solid.reaction);
        const auto delivery = system->set_point_forces(forces, config.sample_radius);
        undelivered += delivery.undelivered_force * window.dt;
        // The window is the fluid step; a window beyond the stable step is split.
        const int pieces =
            std::max(1, static_cast<int>(std::ceil(window.dt / system->stable_dt() - 1e-9)));
        for (int piece = 0; piece < pieces; ++piece) {
          const auto step = system->step(window.dt / pieces);
          impulses.solids += step.external_impulse;
          impulses.wall_viscous += step.wall_viscous_force * (window.dt / pieces);
          impulses.wall_collision += step.wall_collision_impulse;
          impulses.wall_pressure += step.wall_pressure_impulse;
          impulses.fluid_pressure += step.pressure_impulse - step.wall_pressure_impulse;
          if (open_boundaries) open_boundaries->update();
          pcg_iterations += step.pcg_iterations;
          most_pcg_iterations = std::max(most_pcg_iterations, step.pcg_iterations);
          ++window_steps;
        }
        steps += window_steps;
        system->set_point_forces({}, config.sample_radius);
      }
      if (observation) observation->record(*system);
      if (reference) reference->observe(*system, impulses, observation ? &*observation : nullptr);
      if (fishway) fishway->observe(*system, open_boundaries.get());
      for (const auto& solid : solids) {
        const auto velocity =
            system->sample_velocity(solid.positions, config.sample_radius, &water);
        system->sample_surface(solid.positions, config.sample_radius, surface);
        link.publish_samples(solid.name, velocity, water, surface);
      }
      if (system->time() >= next_output - 1e-9 * config.output_interval) {
        writer.write_frame(make_frame(*system, config.frame));
        next_output += config.output_interval;
      }
      participant.done(window_steps, system->stable_dt());
    }
  });
}
