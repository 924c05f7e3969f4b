// The debris_dem process: builds the structure (seed 004 flume, dam and gated debris packing,
// and/or an open box) and the explicit elements, lets a gated packing settle, then (gate removed
// at t = 0) sub-cycles through every coupling window with the ambient flow at its moving
// elements, returning positions, velocities and fluid forces. Reports the capture rate P_V of
// seed 004 eq. 55 and the woody-debris ratio K_w of eq. 54 when there is a dam, the
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
#include "cosim/output/point_series.hpp"
#include "dem_config.hpp"

namespace {

using namespace cosim;

struct BuiltScene {
  dem::Packing packing;
  std::vector<int> explicit_elements;  // the `elements:` list, in order
  double sphere_volume = 0.0;
  double log_volume = 0.0;
  double settle_seconds = 0.0;  // wall time of the settling behind the gate
};

BuiltScene build_scene(dem::DemWorld& world, const dem::DebrisConfig& config) {
  BuiltScene scene;
  if (config.flume) {
    const dem::FlumeSpec& flume = *config.flume;
    dem::add_flume(world, flume, config.structure);
    if (config.roughness) {
      const auto& r = *config.roughness;
      dem::add_bed_roughness(world, r.x0, r.x1, flume.width, r.d_min, r.d_max, r.seed,
                             config.structure);
    }
    if (config.dam) dem::add_grid_dam(world, *config.dam, config.structure);
    if (config.gate) {
      const double x = config.gate->x;
      world.add_gate({x, 0.0, 0.0}, {x, flume.width, 0.0}, {x, flume.width, flume.wall_height},
                     {x, 0.0, flume.wall_height}, config.structure);
    }
  }
  if (config.box) dem::add_open_box(world, config.box->min, config.box->max, config.structure);
  if (config.packing) {
    scene.packing = dem::random_packing(world, *config.packing, config.debris, config.logs);
  }
  // Explicit elements are not checked against the packing (the first sub-step reports an
  // excessive overlap with both element ids).
  for (const auto& e : config.elements) {
    const int id =
        e.log ? world.add_cylinder(e.center, e.axis, 0.5 * e.diameter, e.length, e.material)
              : world.add_sphere(e.center, 0.5 * e.diameter, e.material);
    world.set_velocity(id, e.velocity);
    scene.explicit_elements.push_back(id);
  }
  for (const int i : world.moving_elements()) {
    (world.kind(i) == dem::ElementKind::kCylinder ? scene.log_volume : scene.sphere_volume) +=
        world.volume(i);
  }
  if (config.gate) {
    const auto start = std::chrono::steady_clock::now();
    const double settled_speed = dem::settle(world, config.gate->settle_time);
    scene.settle_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    spdlog::info(
        "{} spheres and {} logs settled for {} s (largest speed {:.3g} m/s, {:.1f} s wall)",
        scene.packing.spheres.size(), scene.packing.logs.size(), config.gate->settle_time,
        settled_speed, scene.settle_seconds);
    world.set_gate_active(false);
  }
  return scene;
}

// Moving elements with their window-mean fluid force, submerged share and local voidage.
output::PointFrame make_frame(const dem::DemWorld& world, const std::vector<int>& elements) {
  output::PointFrame frame;
  frame.time = world.time();
  auto& radius = frame.scalars["radius"];
  auto& length = frame.scalars["length"];
  auto& submerged = frame.scalars["submerged_fraction"];
  auto& voidage = frame.scalars["voidage"];
  auto& velocity = frame.vectors["velocity"];
  auto& spin = frame.vectors["angular_velocity"];
  auto& fluid_force = frame.vectors["fluid_force"];  // N, window mean (drag, pressure, added mass)
  auto& axis = frame.vectors["axis"];
  auto& kind = frame.labels["kind"];  // 0 sphere, 1 cylinder
  const auto& moving = world.moving_elements();
  for (const int element : elements) {
    const auto slot = std::lower_bound(moving.begin(), moving.end(), element);
    if (slot == moving.end() || *slot != element) continue;
    const auto k = static_cast<std::size_t>(slot - moving.begin());
    frame.positions.push_back(world.position(element));
    radius.push_back(world.radius(element));
    length.push_back(world.length(element));
    submerged.push_back(world.submerged_fraction()[k]);
    voidage.push_back(world.voidage()[k]);
    velocity.push_back(world.velocity(element));
    spin.push_back(world.angular_velocity(element));
    fluid_force.push_back(world.window_mean_fluid_force()[k]);
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

void write_structure(const dem::DemWorld& world, const std::filesystem::path& stem) {
  output::PointSeriesWriter structure(stem, "debris_dem structure");
  output::PointFrame fixed;
  fixed.time = world.time();
  for (int element = 0; element < world.element_count(); ++element) {
    if (!world.is_fixed(element) || world.kind(element) == dem::ElementKind::kTriangle) continue;
    fixed.positions.push_back(world.position(element));
    fixed.scalars["radius"].push_back(world.radius(element));
    fixed.scalars["length"].push_back(world.length(element));
    fixed.vectors["velocity"].push_back(world.velocity(element));
    fixed.vectors["axis"].push_back(world.kind(element) == dem::ElementKind::kCylinder
                                        ? world.axis(element)
                                        : Eigen::Vector3d::Zero());
    fixed.labels["kind"].push_back(static_cast<int>(world.kind(element)));
  }
  structure.write_frame(fixed);
  structure.write_frame(triangle_frame(world));
}

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
};

std::string finish_report(const dem::DemWorld& world, const dem::DebrisConfig& config,
                          const BuiltScene& scene, const RunTotals& totals) {
  coupler::MetricsReport report;
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
    for (const auto& e : config.elements) d_max = std::max(d_max, e.log ? 0.0 : e.diameter);
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
  return report.dump();
}

}  // namespace

int main(int argc, char** argv) {
  return coupler::run_process(argc, argv, "debris_dem", [](coupler::ProcessContext& context) {
    auto section = context.section();
    const dem::DebrisConfig config = dem::parse_config(section, context.scene.output_interval);
    // Declare the gravity the DEM really uses (its slope_degrees and gravity_magnitude), so the
    // coupler refuses a scene whose world gravity differs.
    context.declare_frame(3, 0.0, config.parameters.gravity);
    dem::DemWorld world(config.parameters);
    const BuiltScene scene = build_scene(world, config);
    const std::vector<int> debris = world.moving_elements();

    auto& participant = *context.participant;
    const std::size_t moving = debris.size();
    coupler::SolidLink link(participant, context.scene, moving);
    output::PointSeriesWriter writer(context.output_dir() / "debris", "debris_dem");
    write_structure(world, context.output_dir() / "structure");
    Series series(scene.explicit_elements);
    const std::vector<Eigen::Vector3d> no_force(moving, Eigen::Vector3d::Zero());
    const double time_offset = world.time();  // settling time before the run
    double next_output = 0.0;
    RunTotals totals;
    while (true) {
      const coupler::Window window = participant.next_window();
      context.maybe_inject_fault(window.index);
      if (window.finish) {
        series.write(writer);
        participant.finished(finish_report(world, config, scene, totals));
        return;
      }
      if (window.index == 0) {
        writer.write_frame(make_frame(world, debris));
        series.record(0.0, world);
        next_output = config.output_interval;
        link.publish_state(world.element_centers(), world.element_velocities(), no_force);
        participant.done(0);
        continue;
      }
      const auto [begin, end] = link.ambient(window);
      const auto step = world.advance(window.dt, window_fluid(begin, end, window.dt));
      totals.element_substeps += static_cast<int64_t>(step.substeps) * static_cast<int64_t>(moving);
      totals.largest_overlap = std::max(totals.largest_overlap, step.max_overlap_ratio);
      series.record(world.time() - time_offset, world);
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
