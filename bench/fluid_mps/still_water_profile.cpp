// Still water in a 3D tank (still_water_tank_3d) as a plain program: where the time-averaged
// pressure departs from rho g depth. Prints, per lattice layer, the mean pressure of all the
// layer's water, of the water more than `margin` l0 from the side walls, and of the column on the
// tank's axis, each against rho g (H - z) at the particles' mean height, with the floor's wall
// pressure, the 1.5 l0 probes of the hydrostatic reference and the settling of the mean pressure
// in time. docs/validation.md (still_water_3d) has what it found.
//   still_water_profile key=value ...   (keys below, e.g. l0=0.0125 length=0.1 average_from=1;
//   lattice=1 the fcc start of MpsParameters::FillLattice, whose layers the profile bins by)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/kernels.hpp"
#include "cosim/fluid_mps/scenes.hpp"

using namespace cosim::mps;

namespace {

struct Options {
  std::map<std::string, double> values{
      {"l0", 0.01},       {"length", 0.1},         {"width", 0.1},        {"depth", 0.1},
      {"height", 0.15},   {"duration", 2.0},       {"average_from", 1.0}, {"gradient", 3.1},
      {"laplacian", 3.1}, {"density_radius", 2.1}, {"beta", 0.97},        {"walls", 2},
      {"dummies", 2},     {"margin", 3.1},         {"probe_radius", 1.5}, {"collision", 1.0},
      {"mixed", 0},       {"gamma", 0.2},          {"form", 0},           {"probe_scale", 1.0},
      {"shifting", 0.0},  {"lattice", 0}};  // lattice 0: cubic, 1: fcc
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

MpsParameters parameters_of(const Options& o) {
  MpsParameters p;
  p.dimension = 3;
  p.particle_spacing = o["l0"];
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
  p.fill_lattice = static_cast<MpsParameters::FillLattice>(static_cast<int>(o["lattice"]));
  return p;
}

// The time series (every 0.2 s) and the time means from average_from on.
class Profile {
 public:
  // layer: the spacing of the fill's horizontal layers (l0 cubic, the fitted h_z of fcc).
  Profile(const Options& o, double layer)
      : l0_(o["l0"]),
        layer_(layer),
        length_(o["length"]),
        width_(o["width"]),
        depth_(o["depth"]),
        margin_(o["margin"] * o["l0"]),
        probe_radius_(o["probe_radius"] * o["l0"]),
        layers_(static_cast<std::size_t>(std::lround(o["depth"] / layer)) + 2) {
    const double scale = o["probe_scale"];  // probes at 0.025, 0.05, 0.075 m times this
    probe_depths_ = {0.025 * scale, 0.05 * scale, 0.075 * scale};
    std::printf(
        "# t_from t_to  mean p / mean rho g (H - z) of all water, KE per particle [J/kg], "
        "2 x mean z of the water [m], highest water [m]\n");
  }

  // Every step: the window sums; their line every 0.2 s. Returns the fluid's mean u^2/2.
  double watch(const FluidSystem& system) {
    const auto& x = system.positions();
    double kinetic = 0, fluid = 0;
    for (int i = 0; i < system.particle_count(); ++i) {
      if (system.kinds()[i] != ParticleKind::fluid) continue;
      kinetic += 0.5 * system.velocities()[i].squaredNorm();
      ++fluid;
      w_.p += system.pressures()[i];
      w_.expected += rho_g_ * (depth_ - x[i].z());
      w_.z += x[i].z();
      ++w_.n;
      w_.top = std::max(w_.top, x[i].z());
    }
    w_.kinetic += kinetic / fluid;
    ++w_.samples;
    if (system.time() >= w_.start + 0.2 - 1e-9) {
      const double re_g = system.parameters().radius_gradient_over_l0 * l0_;
      const Moments m =
          lattice_moments(system, length_, width_, margin_, depth_ - re_g - 0.5 * l0_);
      std::printf("%.2f %.2f  %.4f  %.3e  %.5f  %.5f  n/n0 %.4f  sum w_g/n0_g %.4f  gain_zz %.4f\n",
                  w_.start, system.time(), w_.p / w_.expected, w_.kinetic / w_.samples,
                  2.0 * w_.z / w_.n, w_.top, m.density, m.weight, m.zz);
      w_ = Window{};
      w_.start = system.time();
    }
    return kinetic / fluid;
  }

  void average(const FluidSystem& system, double kinetic) {
    ++samples_;
    kinetic_sum_ += kinetic;
    const auto& x = system.positions();
    const auto& pr = system.pressures();
    for (int i = 0; i < system.particle_count(); ++i) {
      const Eigen::Vector3d& xi = x[i];
      const bool core = xi.x() > margin_ && xi.x() < length_ - margin_ && xi.y() > margin_ &&
                        xi.y() < width_ - margin_;
      if (system.kinds()[i] == ParticleKind::wall) {
        if (core && std::abs(xi.z() + 0.5 * layer_) < 0.25 * layer_) {  // the floor's top layer
          floor_sum_ += pr[i];
          ++floor_n_;
        }
        continue;
      }
      const int k = static_cast<int>(std::floor(xi.z() / layer_));
      if (system.kinds()[i] != ParticleKind::fluid || k < 0 || k >= int(layers_.size())) continue;
      Layer& layer = layers_[k];
      add(layer.p_all, layer.z_all, layer.n_all, pr[i], xi.z());
      if (core) add(layer.p_core, layer.z_core, layer.n_core, pr[i], xi.z());
      if (std::hypot(xi.x() - 0.5 * length_, xi.y() - 0.5 * width_) < 0.75 * l0_) {
        add(layer.p_axis, layer.z_axis, layer.n_axis, pr[i], xi.z());
      }
    }
    for (std::size_t k = 0; k < probe_depths_.size(); ++k) {
      const Eigen::Vector3d probe(0.5 * length_, 0.5 * width_, depth_ - probe_depths_[k]);
      probe_sum_[k] += hydrostatic_pressure_at(system, probe, probe_radius_);
      for (int i = 0; i < system.particle_count(); ++i) {
        probe_count_[k] +=
            system.kinds()[i] == ParticleKind::fluid && (x[i] - probe).norm() < probe_radius_;
      }
    }
  }

  void print() const {
    std::printf("# mean KE per particle %.3e J/kg\n", kinetic_sum_ / samples_);
    std::printf(
        "# layer  z_mean  n/sample  p_all/rgh  | core: n p/rgh | axis: n p/rgh   [rgh = "
        "rho g (H - z_mean)]\n");
    auto ratio = [&](double ps, double zs, double n) {
      return n > 0 ? (ps / n) / (rho_g_ * (depth_ - zs / n)) : 0.0;
    };
    for (std::size_t k = 0; k < layers_.size(); ++k) {
      const Layer& L = layers_[k];
      if (L.n_all == 0) continue;
      std::printf("%2zu  %.4f  %6.1f  %.4f  | %6.1f %.4f | %5.2f %.4f   p_all %.1f Pa\n", k,
                  L.z_all / L.n_all, L.n_all / samples_, ratio(L.p_all, L.z_all, L.n_all),
                  L.n_core / samples_, ratio(L.p_core, L.z_core, L.n_core), L.n_axis / samples_,
                  ratio(L.p_axis, L.z_axis, L.n_axis), L.p_all / L.n_all);
    }
    std::printf("# floor wall (top layer, core) p / rho g (H + layer/2) = %.4f\n",
                floor_sum_ / floor_n_ / (rho_g_ * (depth_ + 0.5 * layer_)));
    for (std::size_t k = 0; k < probe_depths_.size(); ++k) {
      const double expected = rho_g_ * probe_depths_[k], mean = probe_sum_[k] / samples_;
      std::printf("# probe depth %.3f: %.1f Pa (%+.2f %%), %.1f particles\n", probe_depths_[k],
                  mean, 100.0 * (mean - expected) / expected, probe_count_[k] / samples_);
    }
  }

 private:
  static void add(double& p_sum, double& z_sum, double& n, double p, double z) {
    p_sum += p;
    z_sum += z;
    ++n;
  }
  struct Window {
    double start = 0, p = 0, expected = 0, kinetic = 0, samples = 0, z = 0, n = 0, top = 0;
  };
  double l0_, layer_, length_, width_, depth_, margin_, probe_radius_;
  double rho_g_ = 1000.0 * 9.81;
  std::vector<Layer> layers_;
  std::vector<double> probe_depths_, probe_sum_ = std::vector<double>(3, 0.0),
                                     probe_count_ = std::vector<double>(3, 0.0);
  double floor_sum_ = 0, floor_n_ = 0, kinetic_sum_ = 0, samples_ = 0;
  Window w_;
};

}  // namespace

int main(int argc, char** argv) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  const Options o = parse(argc, argv);
  MpsParameters p = parameters_of(o);
  // The builder sets p's domain and fill stretch before the system takes p.
  ParticleSet particles =
      still_water_tank_3d(p, o["length"], o["width"], o["depth"], o["height"],
                          static_cast<int>(o["walls"]), static_cast<int>(o["dummies"]));
  FluidSystem system(p, std::move(particles));
  const double layer = p.fill_lattice == MpsParameters::FillLattice::fcc
                           ? fcc_layer_spacing_over_l0() * o["l0"] * p.fill_stretch.z()
                           : o["l0"];
  std::printf("# particles %d, n0 %.6f (density radius), fill stretch %.4f %.4f %.4f\n",
              system.particle_count(), system.n0_density(), p.fill_stretch.x(), p.fill_stretch.y(),
              p.fill_stretch.z());
  Profile profile(o, layer);
  const auto start = std::chrono::steady_clock::now();
  while (system.time() < o["duration"] - 1e-9) {
    system.step(system.stable_dt());
    const double kinetic = profile.watch(system);
    if (system.time() >= o["average_from"]) profile.average(system, kinetic);
  }
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("# particles %d  steps %ld  wall %.1f s\n", system.particle_count(),
              system.step_count(), wall);
  profile.print();
  return 0;
}
