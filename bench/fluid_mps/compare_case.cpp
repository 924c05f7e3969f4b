// The Martin & Moyce dam break of dam_break_bench.cpp as a plain program with a fixed time step,
// for the side-by-side run against MPS-Basic (compare_mps_basic.py).
//
//   bench_fluid_mps_compare --cells-per-width N --write-start FILE
//       writes the initial particles ("kind x y z", kind 1 fluid, 2 wall, 3 dummy) and the
//       domain box, which the script turns into MPS-Basic's input;
//   bench_fluid_mps_compare --cells-per-width N [--warmup-steps 200] [--steps 200]
//       [--dt S] [--tolerance 1e-8] [--preconditioner automatic|amg|jacobi|ic|aggregation]
//       [--radii RN,RG,RL] [--surface-threshold 0.97] [--gravity 9.81]
//       runs warmup + timed steps of dt and prints one JSON line: particles, steps, CPU seconds
//       of the timed steps (process clock), wall seconds, mean PCG iterations per timed step,
//       time reached and the surge front.
// Column a x 2a with a = 0.05715 m in a tank 8a x 3a, 2 wall and 2 dummy layers; l0 = a / N.
// Default dt: 0.25 l0 / sqrt(2 g 2a) (the benchmark's max_dt).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <exception>
#include <fstream>
#include <iostream>
#include <string>

#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/scenes.hpp"

namespace {

using cosim::mps::FluidSystem;
using cosim::mps::MpsParameters;
using cosim::mps::ParticleKind;
using cosim::mps::ParticleSet;

constexpr double kColumnWidth = 0.05715;  // a [m]

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

struct Options {
  int cells_per_width = 20;
  long warmup_steps = 200;
  long steps = 200;
  double dt = 0.0;  // 0: the default above
  double tolerance = 1e-8;
  std::string preconditioner = "automatic";
  double radius_density = 2.1, radius_gradient = 2.1, radius_laplacian = 4.0;
  double surface_threshold = 0.97;
  double gravity = 9.81;
  std::string write_start;
};

[[noreturn]] void usage(const std::string& message) {
  std::cerr << "bench_fluid_mps_compare: " << message
            << "\nusage: bench_fluid_mps_compare --cells-per-width N [--write-start FILE | "
               "[--warmup-steps W] [--steps M] [--dt S] [--tolerance T] "
               "[--preconditioner automatic|amg|jacobi|ic|aggregation] [--radii RN,RG,RL] "
               "[--surface-threshold B] [--gravity G]]\n";
  std::exit(2);
}

Options parse(int argc, char** argv) {
  Options o;
  for (int k = 1; k < argc; ++k) {
    const std::string key = argv[k];
    if (k + 1 >= argc) usage("missing value after " + key);
    const std::string value = argv[++k];
    if (key == "--cells-per-width") {
      o.cells_per_width = std::stoi(value);
    } else if (key == "--warmup-steps") {
      o.warmup_steps = std::stol(value);
    } else if (key == "--steps") {
      o.steps = std::stol(value);
    } else if (key == "--dt") {
      o.dt = std::stod(value);
    } else if (key == "--tolerance") {
      o.tolerance = std::stod(value);
    } else if (key == "--preconditioner") {
      o.preconditioner = value;
    } else if (key == "--radii") {
      if (std::sscanf(value.c_str(), "%lf,%lf,%lf", &o.radius_density, &o.radius_gradient,
                      &o.radius_laplacian) != 3) {
        usage("--radii takes RN,RG,RL");
      }
    } else if (key == "--surface-threshold") {
      o.surface_threshold = std::stod(value);
    } else if (key == "--gravity") {
      o.gravity = std::stod(value);
    } else if (key == "--write-start") {
      o.write_start = value;
    } else {
      usage("unknown option " + key);
    }
  }
  if (o.cells_per_width < 2) usage("--cells-per-width must be at least 2");
  return o;
}

MpsParameters::PressurePreconditioner preconditioner(const std::string& name) {
  using P = MpsParameters::PressurePreconditioner;
  if (name == "automatic") return P::automatic;
  if (name == "amg") return P::amg;
  if (name == "jacobi") return P::jacobi;
  if (name == "ic") return P::incomplete_cholesky;
  if (name == "aggregation") return P::aggregation;
  usage("unknown preconditioner " + name);
}

int kind_code(ParticleKind kind) {
  switch (kind) {
    case ParticleKind::fluid:
      return 1;
    case ParticleKind::wall:
      return 2;
    case ParticleKind::dummy:
      return 3;
    case ParticleKind::inactive:
      break;
  }
  return 0;
}

int write_start(const std::string& path, const MpsParameters& p, const ParticleSet& set) {
  std::ofstream out(path);
  out.precision(17);
  out << "# fluid_mps dam_break scene, l0 = " << p.particle_spacing << " m\n";
  out << "# domain " << p.domain.min().x() << ' ' << p.domain.min().y() << ' ' << p.domain.max().x()
      << ' ' << p.domain.max().y() << '\n';
  out << "# kind (1 fluid, 2 wall, 3 dummy) x y z\n";
  for (std::size_t i = 0; i < set.size(); ++i) {
    const Eigen::Vector3d& x = set.positions[i];
    out << kind_code(set.kinds[i]) << ' ' << x.x() << ' ' << x.y() << ' ' << x.z() << '\n';
  }
  return out ? 0 : 1;
}

int run(const Options& o) {
  const double a = kColumnWidth;
  MpsParameters p;
  p.particle_spacing = a / o.cells_per_width;
  p.gravity = Eigen::Vector3d(0.0, -o.gravity, 0.0);
  p.radius_density_over_l0 = o.radius_density;
  p.radius_gradient_over_l0 = o.radius_gradient;
  p.radius_laplacian_over_l0 = o.radius_laplacian;
  p.surface_threshold = o.surface_threshold;
  p.pcg_tolerance = o.tolerance;
  p.pressure_preconditioner = preconditioner(o.preconditioner);
  const double dt =
      o.dt > 0.0 ? o.dt : 0.25 * p.particle_spacing / std::sqrt(2.0 * o.gravity * 2.0 * a);
  p.max_dt = dt;
  ParticleSet set = cosim::mps::dam_break(p, a, 2.0 * a, 8.0 * a, 3.0 * a);
  if (!o.write_start.empty()) return write_start(o.write_start, p, set);

  FluidSystem system(p, set);
  for (long s = 0; s < o.warmup_steps; ++s) system.step(dt);
  long iterations = 0, searches = 0, unconverged = 0;
  double max_speed = 0.0;
  const double cpu0 = process_cpu_seconds(), wall0 = wall_seconds();
  for (long s = 0; s < o.steps; ++s) {
    const cosim::mps::StepReport report = system.step(dt);
    iterations += report.pcg_iterations;
    searches += report.neighbour_searches;
    unconverged += report.pcg_converged ? 0 : 1;
    max_speed = report.max_speed;
  }
  const double cpu = process_cpu_seconds() - cpu0, wall = wall_seconds() - wall0;
  int fluid = 0;
  for (const ParticleKind kind : system.kinds()) fluid += kind == ParticleKind::fluid;
  const double steps = static_cast<double>(std::max(1L, o.steps));
  std::printf(
      "{\"code\": \"fluid_mps\", \"cells_per_width\": %d, \"l0\": %.10g, \"particles\": %d, "
      "\"fluid_particles\": %d, \"dt\": %.10g, \"warmup_steps\": %ld, \"steps\": %ld, "
      "\"cpu_s\": %.6f, \"wall_s\": %.6f, \"mean_iterations\": %.3f, "
      "\"unconverged_steps\": %ld, \"searches_per_step\": %.3f, \"t_end\": %.6f, "
      "\"front_x\": %.6f, \"max_speed\": %.6f, \"tolerance\": %.3g, \"preconditioner\": "
      "\"%s\"}\n",
      o.cells_per_width, p.particle_spacing, system.particle_count(), fluid, dt, o.warmup_steps,
      o.steps, cpu, wall, static_cast<double>(iterations) / steps, unconverged,
      static_cast<double>(searches) / steps, system.time(),
      cosim::mps::surge_front_position(system), max_speed, o.tolerance, o.preconditioner.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(parse(argc, argv));
  } catch (const std::exception& e) {
    std::cerr << "bench_fluid_mps_compare: " << e.what() << '\n';
    return 1;
  }
}
