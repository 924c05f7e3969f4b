// Still water in a 3D tank (still_water_tank_3d) as a plain program: where the time-averaged
// pressure departs from rho g depth. Prints, per lattice layer, the mean pressure of all the
// layer's water, of the water more than `margin` l0 from the side walls, and of the column on the
// tank's axis, each against rho g (H - z) at the particles' mean height, with the floor's wall
// pressure, the 1.5 l0 probes of the hydrostatic reference and the settling of the mean pressure
// in time. docs/validation.md (still_water_3d) has what it found.
//   still_water_profile key=value ...   (keys below, e.g. l0=0.0125 length=0.1 average_from=1)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/kernels.hpp"
#include "cosim/fluid_mps/scenes.hpp"

using namespace cosim::mps;

namespace {

struct Options {
  std::map<std::string, double> values{
      {"l0", 0.01},          {"length", 0.1},      {"width", 0.1},      {"depth", 0.1},
      {"height", 0.15},      {"duration", 2.0},    {"average_from", 1.0}, {"gradient", 3.1},
      {"laplacian", 3.1},    {"density_radius", 2.1}, {"beta", 0.97},   {"walls", 2},
      {"dummies", 2},        {"margin", 3.1},      {"probe_radius", 1.5}, {"collision", 1.0},
      {"mixed", 0},          {"gamma", 0.2},       {"form", 0},
      {"probe_scale", 1.0}, {"shifting", 0.0}};
  double operator[](const std::string& key) const { return values.at(key); }
};

Options parse(int argc, char** argv) {
  Options o;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    const auto eq = arg.find('=');
    if (eq == std::string::npos || !o.values.count(arg.substr(0, eq))) {
      std::fprintf(stderr, "unknown argument %s\n", arg.c_str());
      std::exit(2);
    }
    o.values[arg.substr(0, eq)] = std::atof(arg.c_str() + eq + 1);
  }
  return o;
}

// Means over the water below the top `skip` of the column and `margin` from the side walls of
// the lattice moments that scale the operators: the density sum n_i / n0 (radius r_n), and for
// the gradient radius r_g the sum of w_ij / n0_g and d sum w_ij (z_ij / r_ij)^2 / n0_g, the gain
// of the gradient model (seed 000 eq. (2)) for a pressure linear in z: 1 on the initial lattice.
struct Moments {
  double density = 0, weight = 0, zz = 0;
};

Moments lattice_moments(const FluidSystem& system, double length, double width, double margin,
                        double below) {
  const auto& x = system.positions();
  const auto& kind = system.kinds();
  const MpsParameters& p = system.parameters();
  const double re_n = p.radius_density_over_l0 * p.particle_spacing;
  const double re_g = p.radius_gradient_over_l0 * p.particle_spacing;
  Moments sum;
  int count = 0;
  for (int i = 0; i < system.particle_count(); ++i) {
    const Eigen::Vector3d& xi = x[i];
    if (kind[i] != ParticleKind::fluid || xi.z() > below || xi.x() < margin ||
        xi.x() > length - margin || xi.y() < margin || xi.y() > width - margin) {
      continue;
    }
    Moments m;
    for (int j = 0; j < system.particle_count(); ++j) {
      if (j == i || kind[j] == ParticleKind::inactive) continue;
      const Eigen::Vector3d d = x[j] - xi;
      const double r = d.norm();
      if (r < re_n) m.density += weight(r, re_n);
      if (r < re_g && kind[j] != ParticleKind::dummy) {  // dummies carry no pressure
        m.weight += weight(r, re_g);
        m.zz += weight(r, re_g) * d.z() * d.z() / (r * r);
      }
    }
    sum.density += m.density / system.n0_density();
    sum.weight += m.weight / system.n0_gradient();
    sum.zz += 3.0 * m.zz / system.n0_gradient();
    ++count;
  }
  return {sum.density / count, sum.weight / count, sum.zz / count};
}

struct Layer {
  double p_all = 0, z_all = 0, n_all = 0;  // sums over samples and particles
  double p_core = 0, z_core = 0, n_core = 0;
  double p_axis = 0, z_axis = 0, n_axis = 0;
};

}  // namespace

int main(int argc, char** argv) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  const Options o = parse(argc, argv);
  const double l0 = o["l0"], length = o["length"], width = o["width"], depth = o["depth"];
  MpsParameters p;
  p.dimension = 3;
  p.particle_spacing = l0;
  p.gravity = Eigen::Vector3d(0.0, 0.0, -9.81);
  p.collision_distance_ratio = o["collision"];
  p.radius_density_over_l0 = o["density_radius"];
  p.radius_gradient_over_l0 = o["gradient"];
  p.radius_laplacian_over_l0 = o["laplacian"];
  p.surface_threshold = o["beta"];
  p.pressure_relaxation = o["gamma"];
  if (o["mixed"] > 0) p.source_term = MpsParameters::SourceTerm::mixed;
  p.shifting_coefficient = o["shifting"];
  p.gradient_form = static_cast<MpsParameters::GradientForm>(static_cast<int>(o["form"]));
  FluidSystem system(
      p, still_water_tank_3d(p, length, width, depth, o["height"], static_cast<int>(o["walls"]),
                             static_cast<int>(o["dummies"])));
  const double rho_g = p.density * 9.81;
  const int layers = static_cast<int>(std::lround(depth / l0)) + 2;
  std::vector<Layer> profile(layers);
  const double margin = o["margin"] * l0;
  const double scale = o["probe_scale"];  // probes at 0.025, 0.05, 0.075 m times this
  const std::vector<double> probe_depths{0.025 * scale, 0.05 * scale, 0.075 * scale};
  std::vector<double> probe_sum(3, 0.0), probe_count(3, 0.0);
  double floor_sum = 0, floor_n = 0, kinetic_sum = 0, samples = 0;
  double window_sum = 0, window_expected = 0, window_start = 0;
  const auto start = std::chrono::steady_clock::now();
  long steps = 0;
  std::printf("# t_from t_to  mean p / mean rho g (H - z) of all water, KE per particle [J/kg], "
              "2 x mean z of the water [m], highest water [m]\n");
  double window_kinetic = 0, window_samples = 0, window_z = 0, window_n = 0, top = 0;
  while (system.time() < o["duration"] - 1e-9) {
    system.step(system.stable_dt());
    ++steps;
    const auto& x = system.positions();
    const auto& pr = system.pressures();
    const auto& kind = system.kinds();
    double kinetic = 0, fluid = 0;
    for (int i = 0; i < system.particle_count(); ++i) {
      if (kind[i] != ParticleKind::fluid) continue;
      kinetic += 0.5 * system.velocities()[i].squaredNorm();
      ++fluid;
      window_sum += pr[i];
      window_expected += rho_g * (depth - x[i].z());
      window_z += x[i].z();
      ++window_n;
      top = std::max(top, x[i].z());
    }
    window_kinetic += kinetic / fluid;
    ++window_samples;
    if (system.time() >= window_start + 0.2 - 1e-9) {
      const Moments m = lattice_moments(system, length, width, margin,
                                        depth - p.radius_gradient_over_l0 * l0 - 0.5 * l0);
      std::printf("%.2f %.2f  %.4f  %.3e  %.5f  %.5f  n/n0 %.4f  sum w_g/n0_g %.4f  gain_zz %.4f\n",
                  window_start, system.time(), window_sum / window_expected,
                  window_kinetic / window_samples, 2.0 * window_z / window_n, top, m.density,
                  m.weight, m.zz);
      window_start = system.time();
      window_sum = window_expected = window_kinetic = window_samples = window_z = window_n = 0;
      top = 0;
    }
    if (system.time() < o["average_from"]) continue;
    ++samples;
    kinetic_sum += kinetic / fluid;
    for (int i = 0; i < system.particle_count(); ++i) {
      const Eigen::Vector3d& xi = x[i];
      if (kind[i] == ParticleKind::wall) {
        // The top floor layer (centre -l0/2) away from the side walls.
        if (std::abs(xi.z() + 0.5 * l0) < 0.25 * l0 && xi.x() > margin &&
            xi.x() < length - margin && xi.y() > margin && xi.y() < width - margin) {
          floor_sum += pr[i];
          ++floor_n;
        }
        continue;
      }
      if (kind[i] != ParticleKind::fluid) continue;
      const int k = static_cast<int>(std::floor(xi.z() / l0));
      if (k < 0 || k >= layers) continue;
      Layer& layer = profile[k];
      layer.p_all += pr[i];
      layer.z_all += xi.z();
      ++layer.n_all;
      const bool core = xi.x() > margin && xi.x() < length - margin && xi.y() > margin &&
                        xi.y() < width - margin;
      if (core) {
        layer.p_core += pr[i];
        layer.z_core += xi.z();
        ++layer.n_core;
      }
      if (std::hypot(xi.x() - 0.5 * length, xi.y() - 0.5 * width) < 0.75 * l0) {
        layer.p_axis += pr[i];
        layer.z_axis += xi.z();
        ++layer.n_axis;
      }
    }
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d probe(0.5 * length, 0.5 * width, depth - probe_depths[k]);
      probe_sum[k] += mean_pressure_at(system, probe, o["probe_radius"] * l0);
      int count = 0;
      for (int i = 0; i < system.particle_count(); ++i) {
        count += kind[i] == ParticleKind::fluid && (x[i] - probe).norm() < o["probe_radius"] * l0;
      }
      probe_count[k] += count;
    }
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("# particles %d  steps %ld  wall %.1f s  mean KE per particle %.3e J/kg\n",
              system.particle_count(), steps, wall, kinetic_sum / samples);
  std::printf("# layer  z_mean  n/sample  p_all/rgh  | core: n p/rgh | axis: n p/rgh   [rgh = "
              "rho g (H - z_mean)]\n");
  for (int k = 0; k < layers; ++k) {
    const Layer& L = profile[k];
    if (L.n_all == 0) continue;
    auto ratio = [&](double ps, double zs, double n) {
      return n > 0 ? (ps / n) / (rho_g * (depth - zs / n)) : 0.0;
    };
    std::printf("%2d  %.4f  %6.1f  %.4f  | %6.1f %.4f | %5.2f %.4f   p_all %.1f Pa\n", k,
                L.z_all / L.n_all, L.n_all / samples, ratio(L.p_all, L.z_all, L.n_all),
                L.n_core / samples, ratio(L.p_core, L.z_core, L.n_core), L.n_axis / samples,
                ratio(L.p_axis, L.z_axis, L.n_axis), L.p_all / L.n_all);
  }
  std::printf("# floor wall (top layer, core) p / rho g (H + l0/2) = %.4f\n",
              floor_sum / floor_n / (rho_g * (depth + 0.5 * l0)));
  for (int k = 0; k < 3; ++k) {
    const double expected = rho_g * probe_depths[k];
    std::printf("# probe depth %.3f: %.1f Pa (%+.2f %%), %.1f particles\n", probe_depths[k],
                probe_sum[k] / samples, 100.0 * (probe_sum[k] / samples - expected) / expected,
                probe_count[k] / samples);
  }
  return 0;
}
