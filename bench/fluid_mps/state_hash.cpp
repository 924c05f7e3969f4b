// A fingerprint of a run for changes that must keep the bits: steps the 2D dam break (AMG,
// Jacobi, aggregation, the mixed source term) and the 3D column collapse (Jacobi, aggregation)
// of bench_fluid_mps and prints one line per case with an FNV-1a hash of the bytes of every
// particle's position, velocity and pressure after the run (and of the number densities of the
// particles that are not dummies). Built against two commits and run with OMP_NUM_THREADS=1 and 2,
// equal lines mean equal bits. Also printed, to compare runs that do not keep the bits (argument
// --single-product: the float CG product; --full-rows or --upper-triangle: that CG product in
// every case instead of the automatic choice, upper triangle in 3D): the surge front (largest fluid
// x), the water height at the back wall (largest fluid height within 2 l0 of the smallest fluid x)
// and the mean fluid pressure. The 2D open channel (the soluble moving wall under discharge and
// level control) hashes its boundaries' released volume and measured level as well.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>

#include "cosim/fluid_mps/boundaries.hpp"
#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/scenes.hpp"

namespace {

using namespace cosim::mps;

struct Fnv1a {
  std::uint64_t value = 14695981039346656037ull;
  void add(const void* data, std::size_t bytes) {
    const auto* b = static_cast<const unsigned char*>(data);
    for (std::size_t k = 0; k < bytes; ++k) value = (value ^ b[k]) * 1099511628211ull;
  }
  void add(double v) { add(&v, sizeof v); }
};

// `after_step` (if any) runs after every step: the open boundaries' update.
void report(const char* name, FluidSystem& system, int steps,
            const std::function<void(Fnv1a&)>& after_step = {}) {
  const int up = system.parameters().dimension == 3 ? 2 : 1;
  long iterations = 0;
  Fnv1a state, density, reports;
  for (int s = 0; s < steps; ++s) {
    const StepReport step = system.step(system.stable_dt());
    iterations += step.pcg_iterations;
    // The step's booked sums, so that a change which keeps the state but regroups a report's
    // sums shows.
    for (const Eigen::Vector3d& v :
         {step.collision_impulse, step.wall_collision_impulse, step.body_impulse,
          step.external_impulse, step.wall_viscous_force}) {
      for (int axis = 0; axis < 3; ++axis) reports.add(v[axis]);
    }
    const int counts[] = {step.collisions, step.surface_particles, step.pressure_unknowns};
    reports.add(counts, sizeof counts);
    if (after_step) after_step(state);
  }
  double front = -1e300, back = 1e300, height = -1e300, pressure = 0.0;
  int fluid = 0;
  const double l0 = system.parameters().particle_spacing;
  for (int i = 0; i < system.particle_count(); ++i) {
    if (system.kinds()[i] != ParticleKind::fluid) continue;
    front = std::max(front, system.positions()[i].x());
    back = std::min(back, system.positions()[i].x());
    pressure += system.pressures()[i];
    ++fluid;
  }
  for (int i = 0; i < system.particle_count(); ++i) {
    const Eigen::Vector3d& x = system.positions()[i];
    if (system.kinds()[i] == ParticleKind::fluid && x.x() < back + 2.0 * l0) {
      height = std::max(height, x[up]);
    }
  }
  for (int i = 0; i < system.particle_count(); ++i) {
    for (int axis = 0; axis < 3; ++axis) {
      state.add(system.positions()[i][axis]);
      state.add(system.velocities()[i][axis]);
    }
    state.add(system.pressures()[i]);
    if (system.kinds()[i] != ParticleKind::dummy) density.add(system.number_densities()[i]);
  }
  std::printf(
      "%-28s particles %6d steps %4d t %.9f CG iterations %7ld state %016llx density "
      "%016llx reports %016llx front %.6f m height %.6f m mean fluid pressure %.4f Pa\n",
      name, system.particle_count(), steps, system.time(), iterations,
      static_cast<unsigned long long>(state.value), static_cast<unsigned long long>(density.value),
      static_cast<unsigned long long>(reports.value), front, height, pressure / std::max(1, fluid));
}

// The CG products the command line asks for.
struct Products {
  bool single = false;
  MpsParameters::PressureProduct product = MpsParameters::PressureProduct::automatic;
  void apply(MpsParameters& p) const {
    p.single_precision_product = single;
    p.pressure_product = product;
  }
};

MpsParameters dam_break_parameters(double l0, double a, int dimension, const Products& products) {
  MpsParameters p;
  products.apply(p);
  p.dimension = dimension;
  if (dimension == 3) {
    p.gravity = Eigen::Vector3d(0.0, 0.0, -9.81);
    p.radius_laplacian_over_l0 = 3.1;
  }
  p.particle_spacing = l0;
  p.max_dt = 0.25 * l0 / std::sqrt(9.81 * 2.0 * a);
  return p;
}

}  // namespace

int main(int argc, char** argv) {
  Products products;
  for (int arg = 1; arg < argc; ++arg) {
    if (std::strcmp(argv[arg], "--single-product") == 0) {
      products.single = true;
    } else if (std::strcmp(argv[arg], "--full-rows") == 0) {
      products.product = MpsParameters::PressureProduct::full_rows;
    } else if (std::strcmp(argv[arg], "--upper-triangle") == 0) {
      products.product = MpsParameters::PressureProduct::upper_triangle;
    } else {
      std::fprintf(stderr,
                   "unknown argument %s (--single-product, --full-rows, --upper-triangle)\n",
                   argv[arg]);
      return 2;
    }
  }
  const double a = 0.05715;
  using Pre = MpsParameters::PressurePreconditioner;
  const auto name = [](Pre pre) {
    return pre == Pre::amg ? "AMG" : pre == Pre::jacobi ? "Jacobi" : "aggregation";
  };
  for (const Pre pre : {Pre::amg, Pre::jacobi, Pre::aggregation}) {
    MpsParameters p = dam_break_parameters(a / 40, a, 2, products);
    p.pressure_preconditioner = pre;
    FluidSystem system(p, dam_break(p, a, 2.0 * a, 8.0 * a, 3.0 * a));
    report(("2D dam break a/l0=40 " + std::string(name(pre))).c_str(), system, 150);
  }
  {
    MpsParameters p = dam_break_parameters(a / 40, a, 2, products);
    p.pressure_preconditioner = Pre::jacobi;
    p.source_term = MpsParameters::SourceTerm::mixed;
    FluidSystem system(p, dam_break(p, a, 2.0 * a, 8.0 * a, 3.0 * a));
    report("2D dam break 40 mixed", system, 150);
  }
  for (const Pre pre : {Pre::jacobi, Pre::aggregation}) {
    MpsParameters p = dam_break_parameters(a / 8, a, 3, products);
    p.pressure_preconditioner = pre;
    FluidSystem system(p, dam_break_3d(p, a, 2.0 * a, 4.0 * a, a, 2.0 * a));
    report(("3D column a/l0=8 " + std::string(name(pre))).c_str(), system, 60);
  }
  using Control = OpenBoundarySettings::Control;
  for (const Control control : {Control::discharge, Control::level}) {
    MpsParameters p;
    products.apply(p);
    p.particle_spacing = 0.005;
    p.collision_distance_ratio = 1.0;
    OpenBoundarySettings settings;
    FluidSystem system(p, open_channel(p, settings, 0.3, 0.025, 0.06, 4, 400));
    settings.control = control;
    settings.discharge = 0.01;
    settings.target_level = 0.03;
    settings.velocity = 0.2;
    settings.level_gain = 50.0;
    OpenBoundaries boundaries(system, settings);
    report(control == Control::discharge ? "2D open channel discharge" : "2D open channel level",
           system, 400, [&](Fnv1a& hash) {
             boundaries.update();
             hash.add(boundaries.inflow_volume());
             hash.add(boundaries.measured_level());
             hash.add(boundaries.velocity());
           });
  }
  return 0;
}
