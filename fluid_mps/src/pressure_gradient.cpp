// Pressure-gradient models and particle shifting (issue 16). Formulas from the papers cited at
// each function; the code is ours.
#include "cosim/fluid_mps/pressure_gradient.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "cosim/fluid_mps/operators.hpp"
#include "particle_loops.hpp"

// Loops run in parallel from 4096 items on, as in fluid_step.cpp.
namespace cosim::mps {
namespace {

using Form = MpsParameters::GradientForm;

// p^_i: the smallest pressure of i and its pressure-carrying neighbours within the radius
// (Koshizuka & Oka 1996): subtracting it keeps every pair force repulsive.
double smallest_around(const GradientInput& in, int i) {
  const NeighbourList& list = *in.neighbours;
  const auto& kinds = *in.kinds;
  const auto& p = *in.pressure;
  double smallest = p[i];
  for (std::int64_t k = in.begin(i); k < in.end(i); ++k) {
    const int j = list.index[k];
    if (carries_pressure(kinds[j]) && list.distance[k] < in.radius) {
      smallest = std::min(smallest, p[j]);
    }
  }
  return smallest;
}

// p^_i of every fluid particle (`evaluate`: of those marked), zero for the others.
void neighbourhood_minimum(const GradientInput& in, std::vector<double>& minimum,
                           const std::vector<char>* evaluate) {
  const auto& kinds = *in.kinds;
  const int n = static_cast<int>(kinds.size());
  minimum.assign(n, 0.0);
#pragma omp parallel for schedule(dynamic, kParticleChunk) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    if (!is_fluid(kinds[i]) || (evaluate && !(*evaluate)[i])) continue;
    minimum[i] = smallest_around(in, i);
  }
}

// Unit normal of every wall particle [-]: away from the solid around it, -sum over its wall and
// dummy neighbours of r_wj / |r_wj|^2 w_wj, normalised. It is a property of the wall alone (exact
// along a straight wall), not of where a fluid particle sits over its bumps. Zero for particles
// with a balanced solid neighbourhood (deep inside a wall) and for every other kind.
void wall_normals(const GradientInput& in, std::vector<Eigen::Vector3d>& normal) {
  const NeighbourList& list = *in.neighbours;
  const auto& kinds = *in.kinds;
  const auto& x = *in.positions;
  const int n = static_cast<int>(kinds.size());
  normal.assign(n, Eigen::Vector3d::Zero());
#pragma omp parallel for schedule(dynamic, kParticleChunk) if (n >= 4096)
  for (int w = 0; w < n; ++w) {
    if (kinds[w] != ParticleKind::wall) continue;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double weights = 0.0;
    for (std::int64_t k = in.begin(w); k < in.end(w); ++k) {
      const int j = list.index[k];
      const double r = list.distance[k];
      if (is_fluid(kinds[j]) || is_inactive(kinds[j]) || r >= in.radius) continue;
      const Eigen::Vector3d term =
          gradient_pair_term(1.0, r, in.radius, in.periodic->wrap(x[j] - x[w]));
      sum -= term;
      weights += term.norm();
    }
    if (sum.norm() > 0.1 * weights) normal[w] = sum.normalized();
  }
}

// Sums of the pair terms coefficient_ij r_ij / |r_ij|^2 w_ij of particle i, split into fluid
// and wall partners; with wall normals, also their weighted sum, each turned to face i.
struct PairSums {
  Eigen::Vector3d all = Eigen::Vector3d::Zero();  // fluid + wall, summed in the list's order
  Eigen::Vector3d fluid = Eigen::Vector3d::Zero();
  Eigen::Vector3d wall = Eigen::Vector3d::Zero();
  Eigen::Vector3d wall_geometry = Eigen::Vector3d::Zero();  // the wall pair terms, coefficient 1
  Eigen::Vector3d wall_normal = Eigen::Vector3d::Zero();
  double wall_weight = 0.0;  // sum of w_ij over the wall partners that have a normal
};

template <class Coefficient>
PairSums pair_sums(const GradientInput& in, int i, Coefficient&& coefficient,
                   const std::vector<Eigen::Vector3d>* normals = nullptr) {
  const NeighbourList& list = *in.neighbours;
  const auto& kinds = *in.kinds;
  const auto& x = *in.positions;
  PairSums s;
  for (std::int64_t k = in.begin(i); k < in.end(i); ++k) {
    const int j = list.index[k];
    const double r = list.distance[k];
    if (!carries_pressure(kinds[j]) || r >= in.radius) continue;
    const Eigen::Vector3d offset = in.periodic->wrap(x[j] - x[i]);
    const Eigen::Vector3d term = gradient_pair_term(coefficient(j), r, in.radius, offset);
    s.all += term;
    if (is_fluid(kinds[j])) {
      s.fluid += term;
    } else {
      s.wall += term;
      if (normals) {
        s.wall_geometry += gradient_pair_term(1.0, r, in.radius, offset);
        const Eigen::Vector3d& normal = (*normals)[j];
        if (normal.squaredNorm() > 0.0) {  // particles inside the wall have none
          const double w = weight(r, in.radius);
          s.wall_normal += normal.dot(offset) > 0.0 ? -w * normal : w * normal;
          s.wall_weight += w;
        }
      }
    }
  }
  return s;
}

// The walls' share of the symmetric form with its lattice part pressed onto the local wall
// normal (issue 16). Split sum_w (p_i + p_w) r w / r^2 = sum_w (p_w - p_i) r w / r^2 +
// 2 p_i sum_w r w / r^2: the first part is the pressure difference towards the wall (it carries
// the gradient, along the wall too: hydrostatic at a side wall); the second is a particle wall's
// row of bumps l0 apart times the absolute pressure, whose tangential part locks the fluid into
// the hollows of the wall lattice. Only that part is made smooth, pushing along the normal as the
// explicitly represented polygon walls of Harada et al. (2008) and Mitsume et al. (2015) do. The
// normal at i is the weighted mean of the nearby wall particles' normals. This holds for a
// straight wall only: on a lattice at rest the lattice sums of fluid and wall cancel, and a
// straight wall's sum has no tangential part there, so removing it changes nothing at rest. Near
// a corner or a wall's end the wall's own sum is tilted at rest (the still-water tank's corners
// pumped 30 times the kinetic energy of the minimum form with the projection there), so where the
// nearby normals differ by more than about 10 degrees (their weighted mean shorter than 0.985)
// the wall term is left whole, as in the symmetric form. Needs the fluid pressure p_i: `wall`
// holds sum_w (p_i + p_w) r w / r^2.
Eigen::Vector3d normal_wall_share(const PairSums& s, double p_i) {
  const double length = s.wall_normal.norm();
  if (!(length > 0.985 * s.wall_weight)) return s.wall;
  const Eigen::Vector3d normal = s.wall_normal / length;
  const Eigen::Vector3d lattice = 2.0 * p_i * s.wall_geometry;
  return s.wall - lattice + normal.dot(lattice) * normal;
}

// Particle i and every fluid partner within the radius carry a pressure unknown (none is on
// the free surface): the neighbourhood is full, so the correction matrix only corrects the
// disorder of the arrangement, not the missing half-space above a surface.
bool full_neighbourhood(const GradientInput& in, int i) {
  const auto& unknown = *in.unknown;
  if (unknown[i] < 0) return false;
  const NeighbourList& list = *in.neighbours;
  for (std::int64_t k = in.begin(i); k < in.end(i); ++k) {
    const int j = list.index[k];
    if (list.distance[k] < in.radius && is_fluid((*in.kinds)[j]) && unknown[j] < 0) return false;
  }
  return true;
}

}  // namespace

Eigen::Matrix3d correction_matrix(const GradientInput& in, int i) {
  const NeighbourList& list = *in.neighbours;
  const auto& kinds = *in.kinds;
  const auto& x = *in.positions;
  const int d = in.dimension;
  Eigen::Matrix3d moment = Eigen::Matrix3d::Zero();
  for (std::int64_t k = in.begin(i); k < in.end(i); ++k) {
    const int j = list.index[k];
    const double r = list.distance[k];
    if (!carries_pressure(kinds[j]) || r >= in.radius) continue;
    const Eigen::Vector3d e = in.periodic->wrap(x[j] - x[i]) / r;
    moment += weight(r, in.radius) * e * e.transpose();
  }
  // On a full lattice the moment is n0/d I. A neighbourhood whose weakest direction holds less
  // than a tenth of that cannot be corrected reliably (the inverse would amplify noise tenfold).
  const double full = in.n0 / d;
  Eigen::Matrix3d result = Eigen::Matrix3d::Zero();
  if (d == 2) {
    const Eigen::Matrix2d m = moment.topLeftCorner<2, 2>();
    if (Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(m, Eigen::EigenvaluesOnly)
            .eigenvalues()
            .minCoeff() > 0.1 * full) {
      result.topLeftCorner<2, 2>() = m.inverse();
      return result;
    }
  } else if (Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(moment, Eigen::EigenvaluesOnly)
                 .eigenvalues()
                 .minCoeff() > 0.1 * full) {
    return moment.inverse();
  }
  result.topLeftCorner(d, d).setIdentity();
  return result / full;
}

std::vector<Eigen::Vector3d> corrected_gradient(const GradientInput& in,
                                                const std::vector<double>& field,
                                                const std::vector<double>& reference) {
  const int n = static_cast<int>(in.kinds->size());
  std::vector<Eigen::Vector3d> result(n, Eigen::Vector3d::Zero());
#pragma omp parallel for schedule(dynamic, kParticleChunk) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    if (!carries_pressure((*in.kinds)[i])) continue;
    const PairSums s = pair_sums(in, i, [&](int j) { return field[j] - reference[i]; });
    result[i] = correction_matrix(in, i) * s.all;
  }
  return result;
}

double correction_weight(const GradientInput& in, int i) {
  const NeighbourList& list = *in.neighbours;
  const auto& kinds = *in.kinds;
  double density = 0.0;
  for (std::int64_t k = in.begin(i); k < in.end(i); ++k) {
    const double r = list.distance[k];
    if (!is_inactive(kinds[list.index[k]]) && r < in.radius) density += weight(r, in.radius);
  }
  const double phi = in.solid_fraction ? (*in.solid_fraction)[i] : 0.0;
  const double beta = in.surface_threshold;
  const double t = std::clamp((density / (in.n0 * (1.0 - phi)) - beta) / (1.0 - beta), 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

namespace {

// The matrix `form` applies to particle i's sum: n0/d C_i for the corrected forms where they
// correct, blended by the neighbourhood's fullness for corrected_blended (and for
// corrected_split's Taylor part when `split_taylor`; its repulsion stays plain), else I.
Eigen::Matrix3d form_matrix(Form form, const GradientInput& in, int i, bool split_taylor) {
  const double uncorrected = in.n0 / in.dimension;
  if (form == Form::corrected || (form == Form::corrected_interior && full_neighbourhood(in, i)))
    return uncorrected * correction_matrix(in, i);
  if (form == Form::corrected_blended || (split_taylor && form == Form::corrected_split)) {
    const double w = correction_weight(in, i);
    if (w > 0.0)
      return (1.0 - w) * Eigen::Matrix3d::Identity() + w * uncorrected * correction_matrix(in, i);
  }
  return Eigen::Matrix3d::Identity();
}

// The gradient sum of fluid particle i by `form` and the walls' share of it (see
// pressure_gradients); `minimum` holds p^_i, `normals` the wall normals (symmetric_normal_wall).
void gradient_at(Form form, const GradientInput& in, int i, const std::vector<double>& minimum,
                 const std::vector<Eigen::Vector3d>& normals, Eigen::Vector3d& gradient,
                 Eigen::Vector3d& wall) {
  const auto& p = *in.pressure;
  // The corrected forms return n0/d C_i times their sum, so every form is scaled the same.
  const double uncorrected = in.n0 / in.dimension;
  auto minimum_form = [&] { return pair_sums(in, i, [&](int j) { return p[j] - minimum[i]; }); };
  switch (form) {
    case Form::minimum: {  // Koshizuka & Oka (1996); seed 000 eq. (2) with p^_i
      const PairSums s = minimum_form();
      gradient = s.all;
      wall = s.wall;
      return;
    }
    case Form::symmetric: {  // the pair form of SPH: antisymmetric in i, j
      const PairSums s = pair_sums(in, i, [&](int j) { return p[i] + p[j]; });
      gradient = s.all;
      wall = s.wall;
      return;
    }
    case Form::symmetric_normal_wall: {
      const PairSums s = pair_sums(
          in, i, [&](int j) { return p[i] + p[j]; }, &normals);
      wall = normal_wall_share(s, p[i]);
      gradient = s.fluid + wall;
      return;
    }
    case Form::corrected:             // Khayyer & Gotoh (2011) correction of the minimum form
    case Form::corrected_interior: {  // the same, off the free surface only
      const PairSums s = minimum_form();
      if (form == Form::corrected || full_neighbourhood(in, i)) {
        const Eigen::Matrix3d c = uncorrected * correction_matrix(in, i);
        gradient = c * s.all;
        wall = c * s.wall;
      } else {
        gradient = s.all;
        wall = s.wall;
      }
      return;
    }
    case Form::corrected_blended: {  // (1 - w_i) I + w_i n0/d C_i on the minimum form
      const PairSums s = minimum_form();
      const double w = correction_weight(in, i);
      gradient = s.all;
      wall = s.wall;
      if (w > 0.0) {
        const Eigen::Matrix3d c = uncorrected * correction_matrix(in, i);
        gradient = w < 1.0 ? Eigen::Vector3d((1.0 - w) * s.all + w * (c * s.all)) : c * s.all;
        wall = w < 1.0 ? Eigen::Vector3d((1.0 - w) * s.wall + w * (c * s.wall)) : c * s.wall;
      }
      return;
    }
    case Form::corrected_split: {  // the blend on the Taylor part sum (p_j - p_i) F_ij only
      const PairSums s = minimum_form();
      gradient = s.all;
      wall = s.wall;
      const double w = correction_weight(in, i);
      if (w > 0.0) {
        // sum (p_j - p^_i) F = sum (p_j - p_i) F + (p_i - p^_i) sum F: the first part gets
        // w (n0/d C_i - I) added, the second (the repulsion that keeps p^_i) stays as it is.
        const double excess = p[i] - minimum[i];
        const PairSums unit = pair_sums(in, i, [](int) { return 1.0; });
        const Eigen::Matrix3d change =
            w * (uncorrected * correction_matrix(in, i) - Eigen::Matrix3d::Identity());
        gradient += change * (s.all - excess * unit.all);
        wall += change * (s.wall - excess * unit.wall);
      }
      return;
    }
  }
}

// u_i += J_i dr_i at every shifted particle (shift_particles), J_i the corrected velocity
// gradient (corrected_gradient's sum for a vector field, taken at the shifted particles only);
// every J_i from the velocities before the change, so the result does not depend on the order
// (or the thread count).
void carry_velocities(const GradientInput& in, const std::vector<Eigen::Vector3d>& shift,
                      std::vector<Eigen::Vector3d>& velocities) {
  const NeighbourList& list = *in.neighbours;
  const auto& kinds = *in.kinds;
  const auto& x = *in.positions;
  const int n = static_cast<int>(kinds.size());
  std::vector<Eigen::Vector3d> change(n, Eigen::Vector3d::Zero());
#pragma omp parallel for schedule(dynamic, kParticleChunk) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    if (!is_fluid(kinds[i]) || shift[i].squaredNorm() == 0.0) continue;
    Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
    for (std::int64_t k = in.begin(i); k < in.end(i); ++k) {
      const int j = list.index[k];
      const double r = list.distance[k];
      if (!carries_pressure(kinds[j]) || r >= in.radius) continue;
      const Eigen::Vector3d rij = in.periodic->wrap(x[j] - x[i]);
      sum += (weight(r, in.radius) / (r * r)) * (velocities[j] - velocities[i]) * rij.transpose();
    }
    change[i] = sum * (correction_matrix(in, i) * shift[i]);
  }
  for (int i = 0; i < n; ++i) velocities[i] += change[i];
}

}  // namespace

void pressure_gradients(MpsParameters::GradientForm form, const GradientInput& in,
                        std::vector<Eigen::Vector3d>& gradient, std::vector<Eigen::Vector3d>& wall,
                        std::vector<double>& minimum, const std::vector<char>* evaluate) {
  const auto& kinds = *in.kinds;
  const int n = static_cast<int>(kinds.size());
  gradient.resize(n);  // every entry is set in the loop below
  wall.resize(n);
  if (form == Form::corrected_interior && in.unknown == nullptr) {
    throw std::invalid_argument("pressure_gradients: corrected_interior needs the unknowns");
  }
  // p^_i of a particle is found in the loop, just before its gradient reads it, while its pairs
  // are in cache (the symmetric forms have none: zero).
  minimum.resize(n);
  const bool with_minimum = form != Form::symmetric && form != Form::symmetric_normal_wall;
  std::vector<Eigen::Vector3d> normals;
  if (form == Form::symmetric_normal_wall) wall_normals(in, normals);
#pragma omp parallel for schedule(dynamic, kParticleChunk) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    minimum[i] = 0.0;
    gradient[i] = wall[i] = Eigen::Vector3d::Zero();
    if (!is_fluid(kinds[i]) || (evaluate && !(*evaluate)[i])) continue;
    if (with_minimum) minimum[i] = smallest_around(in, i);
    gradient_at(form, in, i, minimum, normals, gradient[i], wall[i]);
  }
}

void add_full_pressure_repulsion(Form form, const GradientInput& in,
                                 const std::vector<double>& dynamic_minimum,
                                 const std::vector<double>& full_pressure,
                                 const std::vector<double>& fade, const std::vector<char>* evaluate,
                                 std::vector<Eigen::Vector3d>& gradient,
                                 std::vector<Eigen::Vector3d>& wall,
                                 std::vector<double>& full_minimum) {
  if (form == Form::symmetric || form == Form::symmetric_normal_wall) return;  // no p^_i
  const auto& kinds = *in.kinds;
  const auto& q = *in.pressure;
  const int n = static_cast<int>(kinds.size());
  GradientInput full = in;
  full.pressure = &full_pressure;
  neighbourhood_minimum(full, full_minimum, evaluate);
#pragma omp parallel for schedule(dynamic, kParticleChunk) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    if (!is_fluid(kinds[i]) || (evaluate && !(*evaluate)[i])) continue;
    const double extra =
        fade[i] * ((full_pressure[i] - full_minimum[i]) - (q[i] - dynamic_minimum[i]));  // [Pa]
    if (extra == 0.0) continue;
    const PairSums unit = pair_sums(in, i, [](int) { return 1.0; });
    const Eigen::Matrix3d m = form_matrix(form, in, i, false);  // split leaves the repulsion plain
    gradient[i] += extra * (m * unit.all);
    wall[i] += extra * (m * unit.wall);
  }
}

void keep_layer_deviation(Form form, const GradientInput& in, const std::vector<double>& background,
                          double layer_width, const std::vector<char>& evaluate,
                          const std::vector<int>& order, std::vector<Eigen::Vector3d>& taylor,
                          std::vector<Eigen::Vector3d>& gradient) {
  const auto& kinds = *in.kinds;
  const int n = static_cast<int>(kinds.size());
  taylor.resize(n);
  auto counted = [&](int i) { return is_fluid(kinds[i]) && evaluate[i]; };
#pragma omp parallel for schedule(dynamic, kParticleChunk) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    if (!counted(i)) continue;
    const PairSums s = pair_sums(in, i, [&](int j) { return background[j] - background[i]; });
    taylor[i] = form_matrix(form, in, i, true) * s.all;
  }
  // Layer means, summed serially in `order` (the particles' own numbering): the same bits
  // whatever the internal order or the thread count.
  auto layer = [&](int i) {
    return static_cast<std::size_t>(std::max(background[i], 0.0) / layer_width);
  };
  std::vector<Eigen::Vector3d> mean;
  std::vector<int> count;
  for (const int i : order) {
    if (!counted(i)) continue;
    const std::size_t b = layer(i);
    if (b >= mean.size()) {
      mean.resize(b + 1, Eigen::Vector3d::Zero());
      count.resize(b + 1, 0);
    }
    mean[b] += taylor[i];
    ++count[b];
  }
  for (std::size_t b = 0; b < mean.size(); ++b) {
    if (count[b] > 0) mean[b] /= count[b];
  }
#pragma omp parallel for schedule(dynamic, kParticleChunk) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    if (counted(i)) gradient[i] += taylor[i] - mean[layer(i)];
  }
}

double shift_particles(const GradientInput& in, std::vector<Eigen::Vector3d>& velocities,
                       const std::vector<int>& pressure_unknown, const ShiftingOptions& options,
                       std::vector<Eigen::Vector3d>& positions_out) {
  const NeighbourList& list = *in.neighbours;
  const auto& kinds = *in.kinds;
  const auto& x = *in.positions;
  const int n = static_cast<int>(kinds.size());
  auto on_surface = [&](int j) { return is_fluid(kinds[j]) && pressure_unknown[j] < 0; };
  std::vector<Eigen::Vector3d> shift(n, Eigen::Vector3d::Zero());
  const double factor = gradient_factor(in.dimension, in.n0);
#pragma omp parallel for schedule(dynamic, kParticleChunk) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    if (!is_fluid(kinds[i]) || on_surface(i)) continue;
    Eigen::Vector3d concentration_gradient = Eigen::Vector3d::Zero();
    Eigen::Vector3d wall_gradient = Eigen::Vector3d::Zero();
    bool near_surface = false;
    for (std::int64_t k = in.begin(i); k < in.end(i); ++k) {
      const int j = list.index[k];
      const double r = list.distance[k];
      if (r >= in.radius || is_inactive(kinds[j])) continue;
      near_surface = near_surface || on_surface(j);
      const Eigen::Vector3d term =
          gradient_pair_term(1.0, r, in.radius, in.periodic->wrap(x[j] - x[i]));
      concentration_gradient += term;
      if (options.tangential_at_walls && !is_fluid(kinds[j])) wall_gradient += term;
    }
    if (near_surface) continue;
    const double diffusion = options.coefficient * options.particle_spacing * velocities[i].norm() *
                             options.dt;  // [m^2]
    Eigen::Vector3d dr = -diffusion * factor * concentration_gradient;
    if (options.tangential_at_walls && wall_gradient.squaredNorm() > 0.0) {
      const Eigen::Vector3d normal = wall_gradient.normalized();
      dr -= dr.dot(normal) * normal;
    }
    const double length = dr.norm();
    if (length > options.max_shift) dr *= options.max_shift / length;
    shift[i] = dr;
  }
  if (options.taylor) carry_velocities(in, shift, velocities);
  double largest = 0.0;
  for (int i = 0; i < n; ++i) {
    positions_out[i] += shift[i];
    largest = std::max(largest, shift[i].norm());
  }
  return largest;
}

}  // namespace cosim::mps
