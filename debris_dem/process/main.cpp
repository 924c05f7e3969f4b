// The debris_dem process: builds the flume, dam and debris packing, lets the packing settle
// behind its gate, then (gate removed at t = 0) sub-cycles through every coupling window with
// the ambient flow at its moving elements, returning positions, velocities and fluid forces.
// Reports the capture rate P_V of seed 004 eq. 55 and the woody-debris ratio K_w of eq. 54.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>

#include "cosim/coupler/links.hpp"
#include "cosim/coupler/metrics.hpp"
#include "cosim/coupler/process_main.hpp"
#include "cosim/output/point_series.hpp"
#include "dem_config.hpp"

namespace {

using namespace cosim;

output::PointFrame make_frame(const dem::DemWorld& world, const std::vector<int>& elements) {
  output::PointFrame frame;
  frame.time = world.time();
  auto& radius = frame.scalars["radius"];
  auto& length = frame.scalars["length"];
  auto& velocity = frame.vectors["velocity"];
  auto& axis = frame.vectors["axis"];
  auto& kind = frame.labels["kind"];  // 0 sphere, 1 cylinder
  for (const int element : elements) {
    if (world.kind(element) == dem::ElementKind::kTriangle) continue;
    frame.positions.push_back(world.position(element));
    radius.push_back(world.radius(element));
    length.push_back(world.length(element));
    velocity.push_back(world.velocity(element));
    axis.push_back(world.kind(element) == dem::ElementKind::kCylinder ? world.axis(element)
                                                                      : Eigen::Vector3d::Zero());
    kind.push_back(static_cast<int>(world.kind(element)));
  }
  return frame;
}

// Triangles of the structure as points joined by their edges.
output::PointFrame triangle_frame(const dem::DemWorld& world) {
  output::PointFrame frame;
  for (int element = 0; element < world.element_count(); ++element) {
    if (world.kind(element) != dem::ElementKind::kTriangle) continue;
    const int first = static_cast<int>(frame.positions.size());
    for (const auto& vertex : world.triangle_vertices(element)) frame.positions.push_back(vertex);
    frame.segments.push_back({first, first + 1});
    frame.segments.push_back({first + 1, first + 2});
    frame.segments.push_back({first + 2, first});
  }
  return frame;
}

}  // namespace

int main(int argc, char** argv) {
  return coupler::run_process(argc, argv, "debris_dem", [](coupler::ProcessContext& context) {
    auto section = context.section();
    const dem::DebrisConfig config = dem::parse_config(section, context.scene.output_interval);
    dem::DemWorld world(config.parameters);
    dem::add_flume(world, config.flume, config.structure);
    if (config.roughness) {
      const auto& r = *config.roughness;
      dem::add_bed_roughness(world, r.x0, r.x1, config.flume.width, r.d_min, r.d_max, r.seed,
                             config.structure);
    }
    if (config.dam) dem::add_grid_dam(world, *config.dam, config.structure);
    world.add_gate({config.gate_x, 0.0, 0.0}, {config.gate_x, config.flume.width, 0.0},
                   {config.gate_x, config.flume.width, config.flume.wall_height},
                   {config.gate_x, 0.0, config.flume.wall_height}, config.structure);
    const dem::Packing packing =
        dem::random_packing(world, config.packing, config.debris, config.logs);
    const auto settle_start = std::chrono::steady_clock::now();
    const double settled_speed = dem::settle(world, config.settle_time);
    const double settle_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - settle_start).count();
    spdlog::info(
        "{} spheres and {} logs settled for {} s (largest speed {:.3g} m/s, {:.1f} s wall)",
        packing.spheres.size(), packing.logs.size(), config.settle_time, settled_speed,
        settle_seconds);
    world.set_gate_active(false);

    const std::vector<int> debris = packing.all();
    double sphere_volume = 0.0, log_volume = 0.0;
    for (const int element : packing.spheres) sphere_volume += world.volume(element);
    for (const int element : packing.logs) log_volume += world.volume(element);
    double d_max = 0.0;
    for (const auto& sphere_class : config.sphere_classes)
      d_max = std::max(d_max, sphere_class.diameter);

    auto& participant = *context.participant;
    const std::size_t moving = world.moving_elements().size();
    coupler::SolidLink link(participant, context.scene, moving);
    output::PointSeriesWriter writer(context.output_dir() / "debris", "debris_dem");
    {
      output::PointSeriesWriter structure(context.output_dir() / "structure",
                                          "debris_dem structure");
      std::vector<int> fixed;
      for (int element = 0; element < world.element_count(); ++element) {
        if (world.is_fixed(element)) fixed.push_back(element);
      }
      structure.write_frame(make_frame(world, fixed));
      structure.write_frame(triangle_frame(world));
    }
    const std::vector<Eigen::Vector3d> no_force(moving, Eigen::Vector3d::Zero());
    const double time_offset = world.time();  // settling time before the run
    double next_output = 0.0;
    int64_t element_substeps = 0;
    double largest_overlap = 0.0;
    std::vector<Eigen::Vector3d> ambient(moving);
    std::vector<double> water(moving);
    while (true) {
      const coupler::Window window = participant.next_window();
      context.maybe_inject_fault(window.index);
      if (window.finish) {
        coupler::MetricsReport report;
        if (config.dam) {
          report.value("capture_rate_P_V", dem::capture_rate(world, debris, config.dam->x), "");
          // P_V counts everything upstream of the dam, so it only means capture once the debris
          // has arrived: the volume fraction within 0.2 m of the dam or past it.
          double arrived = 0.0, total = 0.0;
          for (const int element : debris) {
            total += world.volume(element);
            if (world.position(element).x() > config.dam->x - 0.2) arrived += world.volume(element);
          }
          report.value("debris_arrived_at_dam", total > 0 ? arrived / total : 0.0, "");
          report.value("gap_ratio_lV_over_dmax", config.dam->vertical_gap / d_max, "");
        }
        report.value("woody_debris_ratio_K_w", log_volume / (sphere_volume + log_volume), "");
        report.info()["spheres"] = packing.spheres.size();
        report.info()["logs"] = packing.logs.size();
        report.info()["element_substeps"] = element_substeps;
        report.info()["settle_wall_seconds"] = settle_seconds;
        report.info()["largest_overlap_ratio"] = largest_overlap;
        report.info()["list_rebuilds"] = world.list_rebuilds();
        participant.finished(report.dump());
        return;
      }
      if (window.index == 0) {
        writer.write_frame(make_frame(world, debris));
        next_output = config.output_interval;
        link.publish_state(world.element_centers(), world.element_velocities(), no_force);
        participant.done(0);
        continue;
      }
      const auto [begin, end] = link.ambient(window);
      // The window's mean flow: the DEM holds it over its sub-steps.
      for (std::size_t i = 0; i < moving; ++i) {
        ambient[i] = 0.5 * (begin.velocity[i] + end.velocity[i]);
        water[i] = 0.5 * (begin.water_fraction[i] + end.water_fraction[i]);
      }
      const auto step = world.advance(window.dt, ambient, water);
      element_substeps += static_cast<int64_t>(step.substeps) * static_cast<int64_t>(moving);
      largest_overlap = std::max(largest_overlap, step.max_overlap_ratio);
      if (world.time() - time_offset >= next_output - 1e-9) {
        writer.write_frame(make_frame(world, debris));
        next_output += config.output_interval;
      }
      link.publish_state(world.element_centers(), world.element_velocities(),
                         world.window_mean_fluid_force());
      participant.done(step.substeps);
    }
  });
}
