// The settling case of settling_scene.hpp as a plain program, for the side-by-side run against
// LIGGGHTS 3.8 (compare_liggghts.py): writes the start positions, or reads them, drops the
// spheres for settle_steps and times timed_steps on one thread. Prints, every report_steps, the
// time, translational and total kinetic energy and the touching contacts (the physics check),
// then one line with the CPU time, wall time and list rebuilds of the timed steps, and a hash of
// the final state.
//
//   debris_dem_compare --write-start FILE [--spheres N]
//   debris_dem_compare --start FILE [--settle-steps 15000] [--timed-steps 4000]
//                      [--report-steps 1000]
//
// Under `valgrind --tool=callgrind --instr-atstart=no` only the timed steps are instrumented
// (the settling steps run at the uninstrumented speed), so the instruction count per timed step
// is a load-independent measure of the step's cost.
#include <chrono>
#include <cstddef>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "settling_scene.hpp"

#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#define COSIM_CALLGRIND_START() CALLGRIND_START_INSTRUMENTATION
#define COSIM_CALLGRIND_STOP() CALLGRIND_STOP_INSTRUMENTATION
#else
#define COSIM_CALLGRIND_START()
#define COSIM_CALLGRIND_STOP()
#endif

namespace {

using cosim::dem::DemWorld;
using cosim::dem::bench::StartSphere;

double process_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// Touching sphere-wall contacts: the five planes of the box (the triangle filter of DemWorld
// gives one contact per plane even where a sphere sits on the diagonal of a face).
int wall_contacts(const DemWorld& world) {
  using cosim::dem::bench::kBoxSide;
  int count = 0;
  for (const int i : world.moving_elements()) {
    const Eigen::Vector3d p = world.position(i);
    const double r = world.radius(i);
    count += (p.z() <= r) + (p.x() <= r) + (kBoxSide - p.x() <= r) + (p.y() <= r) +
             (kBoxSide - p.y() <= r);
  }
  return count;
}

// FNV-1a over the bits of every moving element's position, velocity, angular velocity and
// attitude: equal hashes of two builds mean bitwise equal states, not just equal printed digits.
unsigned long long state_hash(const DemWorld& world) {
  unsigned long long hash = 14695981039346656037ULL;
  const auto add = [&](const double* values, std::size_t count) {
    const auto* bytes = reinterpret_cast<const unsigned char*>(values);
    for (std::size_t k = 0; k < count * sizeof(double); ++k) {
      hash = (hash ^ bytes[k]) * 1099511628211ULL;
    }
  };
  for (const int i : world.moving_elements()) {
    const Eigen::Vector3d p = world.position(i);
    const Eigen::Vector3d v = world.velocity(i);
    const Eigen::Vector3d w = world.angular_velocity(i);
    const Eigen::Quaterniond q = world.orientation(i);
    add(p.data(), 3);
    add(v.data(), 3);
    add(w.data(), 3);
    add(q.coeffs().data(), 4);
  }
  return hash;
}

void report(const DemWorld& world) {
  double translational = 0.0;
  for (const int i : world.moving_elements()) {
    translational += 0.5 * world.mass(i) * world.velocity(i).squaredNorm();
  }
  const int walls = wall_contacts(world);
  std::printf(
      "state t=%.5f ke_trans=%.15e ke_total=%.15e sphere_contacts=%d wall_contacts=%d "
      "rebuilds=%lld\n",
      world.time(), translational, world.kinetic_energy(), world.contact_count() - walls, walls,
      world.list_rebuilds());
}

int write_start(const std::string& path, int spheres) {
  const auto world = cosim::dem::bench::settling_box(spheres, 1);
  std::ofstream out(path);
  out.precision(17);
  out << "# x y z diameter (m), one sphere a line\n";
  for (const int i : world->moving_elements()) {
    const Eigen::Vector3d p = world->position(i);
    out << p.x() << ' ' << p.y() << ' ' << p.z() << ' ' << 2.0 * world->radius(i) << '\n';
  }
  return out ? 0 : 1;
}

int run(const std::string& path, long long settle_steps, long long timed_steps,
        long long report_steps) {
  std::ifstream in(path);
  std::vector<StartSphere> start;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    StartSphere s;
    if (std::sscanf(line.c_str(), "%lf %lf %lf %lf", &s.center.x(), &s.center.y(), &s.center.z(),
                    &s.diameter) != 4) {
      std::cerr << path << ": bad line: " << line << '\n';
      return 1;
    }
    start.push_back(s);
  }
  if (start.empty()) {
    std::cerr << path << ": no spheres\n";
    return 1;
  }
  auto world = cosim::dem::bench::settling_box(start, 1);
  const double dt = cosim::dem::bench::kTimeStep;
  // Coupling windows of 100 steps (1e-3 s) as in bench_settling.cpp; step counts are rounded
  // up to whole windows.
  constexpr long long kWindowSteps = 100;
  const auto steps = [&](long long count) {
    for (long long s = 0; s < count; s += kWindowSteps) {
      world->advance(kWindowSteps * dt, {}, {});
      if (report_steps > 0 && world->step_count() % report_steps == 0) report(*world);
    }
  };
  report(*world);
  steps(settle_steps);
  const long long rebuilds_before = world->list_rebuilds();
  const double cpu_before = process_cpu_seconds();
  const auto wall_before = std::chrono::steady_clock::now();
  COSIM_CALLGRIND_START();
  steps(timed_steps);
  COSIM_CALLGRIND_STOP();
  const double cpu = process_cpu_seconds() - cpu_before;
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_before).count();
  std::printf("timed spheres=%zu steps=%lld cpu_s=%.4f wall_s=%.4f rebuilds=%lld contacts=%d\n",
              start.size(), timed_steps, cpu, wall, world->list_rebuilds() - rebuilds_before,
              world->contact_count());
  std::printf("hash state=%016llx\n", state_hash(*world));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string write_path;
  std::string start_path;
  int spheres = 5000;
  long long settle_steps = 15000;
  long long timed_steps = 4000;
  long long report_steps = 1000;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string key = argv[i];
    const std::string value = argv[i + 1];
    if (key == "--write-start") {
      write_path = value;
    } else if (key == "--start") {
      start_path = value;
    } else if (key == "--spheres") {
      spheres = std::stoi(value);
    } else if (key == "--settle-steps") {
      settle_steps = std::stoll(value);
    } else if (key == "--timed-steps") {
      timed_steps = std::stoll(value);
    } else if (key == "--report-steps") {
      report_steps = std::stoll(value);
    } else {
      std::cerr << "unknown option " << key << '\n';
      return 2;
    }
  }
  if (!write_path.empty()) return write_start(write_path, spheres);
  if (start_path.empty()) {
    std::cerr << "usage: debris_dem_compare --write-start FILE | --start FILE [...]\n";
    return 2;
  }
  return run(start_path, settle_steps, timed_steps, report_steps);
}
