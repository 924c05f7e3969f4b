// mps_basic_driver: MPS-Basic's own Loader, MPSFactory and MPS::stepForward(), stepped and timed
// here instead of in its Simulation (which also writes output files and prints every step).
// Built by CMakeLists.txt beside this file against an MPS-Basic source tree outside this
// repository; compare_mps_basic.py runs it.
//
//   mps_basic_driver --setting settings.yml --output EMPTY_DIR [--warmup-steps 200]
//                    [--steps 200] [--tolerance T] [--write-final FILE]
//
// Prints one JSON line: particles, steps, CPU seconds of the timed steps (process clock), wall
// seconds, mean BiCGSTAB iterations per timed step, time reached and the surge front (largest x
// of the fluid within 2 l0 of the bed y = 0, plus l0 / 2, as fluid_mps' surge_front_position).
// --tolerance: relative residual of BiCGSTAB (solver_probe.hpp); none or <= 0: Eigen's default.
// --write-final: the particles after the last step, in MPS-Basic's prof layout.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <string>

#include "input.hpp"
#include "loader.hpp"
#include "mps.hpp"
#include "mps_factory.hpp"

namespace {

double g_tolerance = 0.0;
long g_iterations = 0;
long g_solves = 0;
double g_worst_residual = 0.0;

double process_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double wall_seconds() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

[[noreturn]] void usage(const std::string& message) {
  std::cerr << "mps_basic_driver: " << message
            << "\nusage: mps_basic_driver --setting FILE --output DIR [--warmup-steps W] "
               "[--steps M] [--tolerance T] [--write-final FILE]\n";
  std::exit(2);
}

}  // namespace

namespace mps_basic_probe {
double tolerance() {
  return g_tolerance;
}
void record(long iterations, double relative_residual) {
  g_iterations += iterations;
  ++g_solves;
  g_worst_residual = std::max(g_worst_residual, relative_residual);
}
}  // namespace mps_basic_probe

int main(int argc, char** argv) {
  std::filesystem::path setting, output;
  std::string write_final;
  long warmup_steps = 200, steps = 200;
  for (int k = 1; k < argc; ++k) {
    const std::string key = argv[k];
    if (k + 1 >= argc) usage("missing value after " + key);
    const std::string value = argv[++k];
    if (key == "--setting") {
      setting = value;
    } else if (key == "--output") {
      output = value;
    } else if (key == "--warmup-steps") {
      warmup_steps = std::stol(value);
    } else if (key == "--steps") {
      steps = std::stol(value);
    } else if (key == "--tolerance") {
      g_tolerance = std::stod(value);
    } else if (key == "--write-final") {
      write_final = value;
    } else {
      usage("unknown option " + key);
    }
  }
  if (setting.empty() || output.empty()) usage("--setting and --output are required");
  std::filesystem::create_directories(output);

  Loader loader;
  const Input input = loader.load(setting, output);
  MPS mps = MPSFactory::create(input);
  const double dt = input.settings.dt;
  const double l0 = input.settings.particleDistance;

  for (long s = 0; s < warmup_steps; ++s) mps.stepForward();
  g_iterations = 0;
  g_solves = 0;
  g_worst_residual = 0.0;
  const double cpu0 = process_cpu_seconds(), wall0 = wall_seconds();
  for (long s = 0; s < steps; ++s) mps.stepForward();
  const double cpu = process_cpu_seconds() - cpu0, wall = wall_seconds() - wall0;

  int fluid = 0, ghosts = 0;
  double front = -std::numeric_limits<double>::infinity();
  for (const Particle& p : mps.particles) {
    if (p.type == ParticleType::Ghost) ++ghosts;
    if (p.type != ParticleType::Fluid) continue;
    ++fluid;
    if (p.position.y() <= 2.0 * l0) front = std::max(front, p.position.x());
  }
  if (!write_final.empty()) {
    std::ofstream out(write_final);
    out.precision(17);
    out << input.startTime + static_cast<double>(warmup_steps + steps) * dt << '\n'
        << mps.particles.size() << '\n';
    for (const Particle& p : mps.particles) {
      out << static_cast<int>(p.type) << ' ' << p.position.x() << ' ' << p.position.y() << ' '
          << p.position.z() << ' ' << p.velocity.x() << ' ' << p.velocity.y() << ' '
          << p.velocity.z() << '\n';
    }
  }
  std::printf(
      "{\"code\": \"MPS-Basic\", \"l0\": %.10g, \"particles\": %d, \"fluid_particles\": %d, "
      "\"ghost_particles\": %d, \"dt\": %.10g, \"warmup_steps\": %ld, \"steps\": %ld, "
      "\"cpu_s\": %.6f, \"wall_s\": %.6f, \"mean_iterations\": %.3f, \"solves\": %ld, "
      "\"worst_relative_residual\": %.3g, \"t_end\": %.6f, \"front_x\": %.6f, \"tolerance\": "
      "%.3g, \"courant\": %.4f}\n",
      l0, mps.particles.size(), fluid, ghosts, dt, warmup_steps, steps, cpu, wall,
      static_cast<double>(g_iterations) / static_cast<double>(std::max(1L, steps)), g_solves,
      g_worst_residual, input.startTime + static_cast<double>(warmup_steps + steps) * dt,
      front + 0.5 * l0, g_tolerance, mps.courant);
  return 0;
}
