#include "debris_scene.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>

namespace cosim::dem {

BuiltScene build_scene(DemWorld& world, const DebrisConfig& config) {
  BuiltScene scene;
  if (config.flume) {
    const FlumeSpec& flume = *config.flume;
    add_flume(world, flume, config.structure);
    if (config.roughness) {
      const auto& r = *config.roughness;
      add_bed_roughness(world, r.x0, r.x1, flume.width, r.d_min, r.d_max, r.seed, config.structure);
    }
    if (config.dam) add_grid_dam(world, *config.dam, config.structure);
    if (config.gate) {
      const double x = config.gate->x;
      world.add_gate({x, 0.0, 0.0}, {x, flume.width, 0.0}, {x, flume.width, flume.wall_height},
                     {x, 0.0, flume.wall_height}, config.structure);
    }
  }
  if (config.box) add_open_box(world, config.box->min, config.box->max, config.structure);
  for (const auto& mesh : config.walls) {
    for (const auto& t : mesh) world.add_triangle(t.a, t.b, t.c, config.structure);
  }
  if (config.packing) {
    scene.packing = random_packing(world, *config.packing, config.debris, config.logs);
  }
  // Explicit elements are not checked against the packing (the first sub-step reports an
  // excessive overlap with both element ids).
  for (const auto& e : config.elements) {
    const int id =
        e.is_log() ? world.add_cylinder(e.center, e.axis, 0.5 * e.diameter, e.length, e.material)
                   : world.add_sphere(e.center, 0.5 * e.diameter, e.material);
    world.set_velocity(id, e.velocity);
    scene.explicit_elements.push_back(id);
  }
  for (const int i : world.moving_elements()) {
    (world.kind(i) == ElementKind::kCylinder ? scene.log_volume : scene.sphere_volume) +=
        world.volume(i);
  }
  if (config.gate) {
    const auto start = std::chrono::steady_clock::now();
    const double settled_speed = settle(world, config.gate->settle_time);
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
output::PointFrame make_frame(const DemWorld& world, const std::vector<int>& elements) {
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
    axis.push_back(world.kind(element) == ElementKind::kCylinder ? world.axis(element)
                                                                 : Eigen::Vector3d::Zero());
    kind.push_back(static_cast<int>(world.kind(element)));
  }
  return frame;
}

// Triangles of the structure as points joined by their edges.
namespace {

output::PointFrame triangle_frame(const DemWorld& world) {
  output::PointFrame frame;
  for (int element = 0; element < world.element_count(); ++element) {
    if (world.kind(element) != ElementKind::kTriangle) continue;
    const int first = static_cast<int>(frame.positions.size());
    for (const auto& vertex : world.triangle_vertices(element)) frame.positions.push_back(vertex);
    frame.segments.push_back({first, first + 1});
    frame.segments.push_back({first + 1, first + 2});
    frame.segments.push_back({first + 2, first});
  }
  return frame;
}

}  // namespace

void write_structure(const DemWorld& world, const std::filesystem::path& stem) {
  output::PointSeriesWriter structure(stem, "debris_dem structure");
  output::PointFrame fixed;
  fixed.time = world.time();
  for (int element = 0; element < world.element_count(); ++element) {
    if (!world.is_fixed(element) || world.kind(element) == ElementKind::kTriangle) continue;
    fixed.positions.push_back(world.position(element));
    fixed.scalars["radius"].push_back(world.radius(element));
    fixed.scalars["length"].push_back(world.length(element));
    fixed.vectors["velocity"].push_back(world.velocity(element));
    fixed.vectors["axis"].push_back(world.kind(element) == ElementKind::kCylinder
                                        ? world.axis(element)
                                        : Eigen::Vector3d::Zero());
    fixed.labels["kind"].push_back(static_cast<int>(world.kind(element)));
  }
  structure.write_frame(fixed);
  structure.write_frame(triangle_frame(world));
}

}  // namespace cosim::dem
