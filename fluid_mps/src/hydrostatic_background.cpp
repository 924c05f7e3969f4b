// Hydrostatic background of the pressure gradient (issue 16); see the header for the model.
#include "cosim/fluid_mps/hydrostatic_background.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace cosim::mps {
namespace {

constexpr int kSmoothingBins = 2;  // eta is averaged over the bins within this many either way
// A vertical gap of more than this many l0 between the fluid particles of a bin is air (a column
// bin of width l0 has a particle about every l0; an fcc lattice leaves gaps up to 1.6 l0).
constexpr double kLayerGap = 3.0;
// No trust within this many depths of the water over a brink or a crest (the pressure over a free
// overfall departs from hydrostatic about 3-4 critical depths upstream of the brink: Rouse 1936;
// Chow 1959, ch. 3). fishway_overflow at l0 = 1 cm, crest 1: 17.4 % without it, 2.5 % with 3.
constexpr double kFeatureDepths = 3.0;

// Column bins over the horizontal axes (one in 2D, two in 3D) and the surface height of each.
class SurfaceHeights {
 public:
  explicit SurfaceHeights(const BackgroundInput& in) : in_(in) {
    const Eigen::Vector3d& g = in.gravity;
    for (int k = 1; k < in.dimension; ++k) {
      if (std::abs(g[k]) > std::abs(g[up_])) up_ = k;
    }
    g_up_ = std::abs(g[up_]);
    sign_ = g[up_] < 0.0 ? 1.0 : -1.0;
    int next = 0;
    for (int k = 0; k < in.dimension; ++k) {
      if (k != up_) axis_[next++] = k;
    }
    const auto& x = *in.positions;
    const auto& kinds = *in.kinds;
    periodic_ = in.periodic && in.periodic->enabled && axis_[0] == 0;
    for (int a = 0; a < in.dimension - 1; ++a) {
      double low = std::numeric_limits<double>::infinity(), high = -low;
      for (std::size_t i = 0; i < x.size(); ++i) {
        if (!carries_pressure(kinds[i])) continue;
        low = std::min(low, x[i][axis_[a]]);
        high = std::max(high, x[i][axis_[a]]);
      }
      if (a == 0 && periodic_) {
        origin_[0] = in.periodic->x_min;
        bins_[0] =
            std::max(1, static_cast<int>(std::lround(in.periodic->length() / in.particle_spacing)));
        width_[0] = in.periodic->length() / bins_[0];
      } else if (low <= high) {
        origin_[a] = low - 0.5 * in.particle_spacing;
        width_[a] = in.particle_spacing;
        bins_[a] = static_cast<int>(std::floor((high - origin_[a]) / width_[a])) + 1;
      }
    }
    // Period's drop: the copy one period downstream lies lower by `drop` along y.
    if (periodic_ && up_ == 1) drop_ = sign_ * in.periodic->drop;
    smooth(surfaces());
  }

  // p_b and its gradient at x, and the trust S of its column apart (see the header).
  void background(const Eigen::Vector3d& x, double& pressure, Eigen::Vector3d& gradient,
                  double& trust, double& fade) const {
    pressure = 0.0;
    gradient.setZero();
    trust = 0.0;
    fade = 0.0;
    double eta = 0.0, column_trust = 0.0;
    std::array<double, 2> eta_slope{0.0, 0.0}, unused{0.0, 0.0};
    if (!interpolate(smoothed_, true, x, eta, eta_slope)) return;
    interpolate(trust_, false, x, column_trust, unused);
    const double depth = eta - height(x);
    if (depth <= 0.0) return;
    trust = std::max(column_trust, 0.0);
    const double delta = in_.fade_depth > 0.0 ? in_.fade_depth : in_.taper_depth;
    const double rho_g = in_.density * g_up_;
    if (in_.blend_fade) {
      // Linear p_b, and the fade on the weight of the background's estimate: every field the
      // operator sees stays linear in water at rest (a curved q in the layer stirs it).
      pressure = rho_g * depth;
      fade = 1.0;
      if (delta > 0.0) trust *= std::min(depth / delta, 1.0);
      for (int a = 0; a < in_.dimension - 1; ++a) gradient[axis_[a]] = rho_g * eta_slope[a];
      gradient[up_] = -rho_g * sign_;
      return;
    }
    // Tapered over the surface layer: f(d) = d^2 / (2 delta) below delta, d - delta / 2 deeper
    // (continuous with its slope f' = min(d / delta, 1)).
    const double f = depth < delta ? 0.5 * depth * depth / delta : depth - 0.5 * delta;
    const double df = depth < delta ? depth / delta : 1.0;
    pressure = rho_g * f;
    fade = df;
    for (int a = 0; a < in_.dimension - 1; ++a) gradient[axis_[a]] = rho_g * (df * eta_slope[a]);
    gradient[up_] = -rho_g * df * sign_;
  }

 private:
  static constexpr double kEmpty = -std::numeric_limits<double>::infinity();
  // Per column bin: the surface of its lowest layer of water, and whether a wall holds it up
  // (surfaces()).
  struct Columns {
    std::vector<double> surface;
    std::vector<double> bottom;  // the lowest water of the layer (the bed under it, l0 / 2 up)
    std::vector<char> supported;
    std::vector<char> below_top;  // 3D: the bin holds no particle of the top layer (surfaces())
  };

  // eta of each bin: the mean surface over the non-empty bins of its window (two bins either
  // way); S: the trust in it (see trust()).
  void smooth(const Columns& columns) {
    const std::vector<double>& surface = columns.surface;
    smoothed_.assign(surface.size(), kEmpty);
    trust_.assign(surface.size(), kEmpty);
    // S looks as far as the operator reaches from the window's edge: a brink or a nappe within
    // r_e of the particles that use this bin's eta makes their water non-hydrostatic.
    const int reach =
        kSmoothingBins + (in_.taper_depth > 0.0
                              ? static_cast<int>(std::ceil(in_.taper_depth / in_.particle_spacing))
                              : 0);
    const int reach1 = in_.dimension == 3 ? reach : 0;
    for (int b1 = 0; b1 < bins_[1]; ++b1) {
      for (int b0 = 0; b0 < bins_[0]; ++b0) {
        double sum = 0.0, lowest = -kEmpty, highest = kEmpty;
        double lowest_bed = -kEmpty, highest_bed = kEmpty;
        double sum_below = 0.0;  // the bins below the top layer, used only if all are
        int count = 0, count_below = 0;
        bool held = true;  // every column within reach rests on a wall
        for (int k1 = -reach1; k1 <= reach1; ++k1) {
          for (int k0 = -reach; k0 <= reach; ++k0) {
            const double h = lookup(surface, b0 + k0, b1 + k1);
            if (h == kEmpty) continue;
            held = held && supported(columns, b0 + k0, b1 + k1);
            const double bed = lookup(columns.bottom, b0 + k0, b1 + k1);
            lowest_bed = std::min(lowest_bed, bed);
            highest_bed = std::max(highest_bed, bed);
            lowest = std::min(lowest, h);
            highest = std::max(highest, h);
            if (std::abs(k0) > kSmoothingBins || std::abs(k1) > kSmoothingBins) continue;
            if (columns.below_top[wrapped(b0 + k0, b1 + k1)]) {
              sum_below += h;
              ++count_below;
              continue;
            }
            sum += h;
            ++count;
          }
        }
        if (count + count_below == 0) continue;
        smoothed_[index(b0, b1)] = count > 0 ? sum / count : sum_below / count_below;
        // A step in the bed within reach (a crest, the top of a partition, a brink's drop):
        // water flows over it, not hydrostatic either.
        trust_[index(b0, b1)] =
            held ? trust(lowest, highest) * trust(lowest_bed, highest_bed) : 0.0;
      }
    }
    distrust_near_features(columns);
  }
  // S = 0 within kFeatureDepths times the depth of the water over a feature (a column no wall
  // holds up, the higher side of a step in the bed), beyond the operator's reach where that is
  // farther: the streamlines over a brink or a crest curve, and the pressure departs from
  // hydrostatic, a few depths upstream of it.
  void distrust_near_features(const Columns& columns) {
    const double k = kFeatureDepths;
    const double l0 = in_.particle_spacing;
    // A step in the bed: more than the fade-in depth, and more than the bottoms of disordered
    // water or a sloping bed differ from bin to bin.
    const double step = std::max(in_.taper_depth, 2.0 * l0);
    const int side1 = in_.dimension == 3 ? 1 : 0;
    for (int b1 = 0; b1 < bins_[1]; ++b1) {
      for (int b0 = 0; b0 < bins_[0]; ++b0) {
        const double h = lookup(columns.surface, b0, b1);
        if (h == kEmpty) continue;
        const double bed = lookup(columns.bottom, b0, b1);
        bool feature = !supported(columns, b0, b1);
        for (int k1 = -side1; k1 <= side1 && !feature; ++k1) {
          for (int k0 = -1; k0 <= 1; ++k0) {
            const double other = lookup(columns.bottom, b0 + k0, b1 + k1);
            if (other != kEmpty && bed - other > step) feature = true;
          }
        }
        if (!feature) continue;
        const int radius = static_cast<int>(std::ceil(k * (h - bed) / l0));
        const int radius1 = in_.dimension == 3 ? radius : 0;
        for (int k1 = -radius1; k1 <= radius1; ++k1) {
          for (int k0 = -radius; k0 <= radius; ++k0) {
            const int c0 = b0 + k0, c1 = b1 + k1;
            if (c1 < 0 || c1 >= bins_[1]) continue;
            if (!periodic_ && (c0 < 0 || c0 >= bins_[0])) continue;
            const std::size_t c = wrapped(c0, c1);
            if (trust_[c] != kEmpty) trust_[c] = 0.0;
          }
        }
      }
    }
  }
  std::size_t wrapped(int b0, int b1) const {
    if (periodic_) b0 = ((b0 % bins_[0]) + bins_[0]) % bins_[0];
    return index(b0, b1);
  }
  bool supported(const Columns& columns, int b0, int b1) const {
    return columns.supported[wrapped(b0, b1)] != 0;
  }

  // The free surface of each bin: half a spacing above the top particle of its lowest layer of
  // water (as water_level() reads it), the layer ending at the first gap of more than
  // kLayerGap l0 between heights. Water above such a gap (a nappe over the pool it falls into,
  // a jet, a splash) is not the column's: it is not held up by the water below. A column whose
  // lowest water has no wall within the gap below or beside it (in its bin or the next) is
  // not held up either (a nappe past a brink, a falling jet): `supported` is false there.
  Columns surfaces() const {
    const auto& x = *in_.positions;
    const auto& kinds = *in_.kinds;
    const std::size_t bin_count = static_cast<std::size_t>(bins_[0]) * bins_[1];
    std::vector<std::size_t> start(bin_count + 1, 0), bin(x.size(), 0);
    for (std::size_t i = 0; i < x.size(); ++i) {
      if (!is_fluid(kinds[i])) continue;
      bin[i] = bin_of(x[i]);
      ++start[bin[i] + 1];
    }
    for (std::size_t b = 0; b < bin_count; ++b) start[b + 1] += start[b];
    std::vector<double> heights(start.back());
    std::vector<std::size_t> next(start.begin(), start.end() - 1);
    for (std::size_t i = 0; i < x.size(); ++i) {
      if (is_fluid(kinds[i])) heights[next[bin[i]]++] = height(x[i]);
    }
    for (std::size_t b = 0; b < bin_count; ++b) {
      std::sort(heights.begin() + static_cast<std::ptrdiff_t>(start[b]),
                heights.begin() + static_cast<std::ptrdiff_t>(start[b + 1]));
    }
    // The layers are read off the band of the bin and its neighbours (3 l0 wide): within one
    // bin of width l0, disordered particles leave vertical gaps of 4 l0 inside the water.
    const double gap = kLayerGap * in_.particle_spacing;
    const int side1 = in_.dimension == 3 ? 1 : 0;
    Columns columns{std::vector<double>(bin_count, kEmpty), std::vector<double>(bin_count, kEmpty),
                    std::vector<char>(bin_count, 0), std::vector<char>(bin_count, 0)};
    std::vector<double>& bottom = columns.bottom;
    std::vector<double> band;
    for (int b1 = 0; b1 < bins_[1]; ++b1) {
      for (int b0 = 0; b0 < bins_[0]; ++b0) {
        const std::size_t b = index(b0, b1);
        if (start[b] == start[b + 1]) continue;
        band.clear();
        for_neighbour_bins(b0, b1, side1, [&](std::size_t c) {
          band.insert(band.end(), heights.begin() + static_cast<std::ptrdiff_t>(start[c]),
                      heights.begin() + static_cast<std::ptrdiff_t>(start[c + 1]));
        });
        std::sort(band.begin(), band.end());
        auto top = band.begin();
        while (top + 1 != band.end() && *(top + 1) - *top <= gap) ++top;
        // The bin's own highest particle in that layer.
        const auto own_first = heights.begin() + static_cast<std::ptrdiff_t>(start[b]);
        const auto own_end = std::upper_bound(
            own_first, heights.begin() + static_cast<std::ptrdiff_t>(start[b + 1]), *top);
        if (own_end == own_first) continue;  // all its water is above the layer
        columns.surface[b] = *(own_end - 1) + 0.5 * in_.particle_spacing;
        // In 3D a bin of l0 x l0 holds on average about one particle of the top layer (0.79 on
        // an fcc (001) face), so a bin without one reads the layer below, 0.8 l0 lower, in a
        // pattern the mean over the window leaves 0.13 l0 of (slopes up to 0.08, each a
        // sideways rho g slope on the water below): such a bin, more than half a spacing below
        // the highest water of its band, is left out of the mean (smooth()). A surface steeper
        // than about 1/4 across the band leaves its lower bins out as well and reads up to
        // l0 / 2 high there. In 2D a bin of width l0 holds a particle of every layer.
        columns.below_top[b] =
            in_.dimension == 3 && *top - *(own_end - 1) > 0.5 * in_.particle_spacing;
        bottom[b] = band.front();
      }
    }
    // Walls within the gap of a column's bottom, in its bin or the next either way (a wall
    // particle on a bin edge may fall on either side).
    for (std::size_t i = 0; i < x.size(); ++i) {
      if (is_fluid(kinds[i]) || !carries_pressure(kinds[i])) continue;
      std::array<int, 2> b{0, 0};
      if (!unclamped_bin(x[i], b)) continue;
      const double h = height(x[i]);
      for_neighbour_bins(b[0], b[1], side1, [&](std::size_t c) {
        if (bottom[c] != kEmpty && std::abs(h - bottom[c]) <= gap) columns.supported[c] = 1;
      });
    }
    return columns;
  }
  // Calls visit(bin index) for (b0, b1) and its neighbours one bin either way along axis 0 (and
  // `side1` along axis 1), wrapping a periodic axis 0.
  template <class Visit>
  void for_neighbour_bins(int b0, int b1, int side1, Visit&& visit) const {
    for (int k1 = -side1; k1 <= side1; ++k1) {
      for (int k0 = -1; k0 <= 1; ++k0) {
        int c0 = b0 + k0;
        const int c1 = b1 + k1;
        if (periodic_) c0 = (c0 + bins_[0]) % bins_[0];
        if (c0 < 0 || c0 >= bins_[0] || c1 < 0 || c1 >= bins_[1]) continue;
        visit(index(c0, c1));
      }
    }
  }
  // The bin of x without clamping; false outside the bins (a wall beyond the water).
  bool unclamped_bin(const Eigen::Vector3d& x, std::array<int, 2>& b) const {
    for (int a = 0; a < in_.dimension - 1; ++a) {
      const double coordinate = a == 0 && periodic_ ? in_.periodic->fold(x[axis_[a]]) : x[axis_[a]];
      b[a] = static_cast<int>(std::floor((coordinate - origin_[a]) / width_[a]));
      if (b[a] < 0 || b[a] >= bins_[a]) {
        if (!(a == 0 && periodic_)) return false;
        b[a] = std::clamp(b[a], 0, bins_[a] - 1);  // a fold that rounds onto the seam
      }
    }
    return true;
  }

  double height(const Eigen::Vector3d& x) const { return sign_ * x[up_]; }
  // S of a bin from the lowest and highest surface within its trust window: 1 where they span
  // at most delta (a gently sloping surface, nearly hydrostatic water), 0 from 2 delta on, a
  // smoothstep between. With no taper depth, 1.
  double trust(double lowest, double highest) const {
    const double delta = in_.taper_depth;
    if (!(delta > 0.0)) return 1.0;
    const double t = std::clamp((2.0 * delta - (highest - lowest)) / delta, 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
  }
  std::size_t index(int b0, int b1) const {
    return static_cast<std::size_t>(b1) * bins_[0] + static_cast<std::size_t>(b0);
  }
  std::size_t bin_of(const Eigen::Vector3d& x) const {
    std::array<int, 2> b{0, 0};
    for (int a = 0; a < in_.dimension - 1; ++a) {
      const double coordinate = a == 0 && periodic_ ? in_.periodic->fold(x[axis_[a]]) : x[axis_[a]];
      b[a] = std::clamp(static_cast<int>(std::floor((coordinate - origin_[a]) / width_[a])), 0,
                        bins_[a] - 1);
    }
    return index(b[0], b[1]);
  }
  // (Bi)linear interpolation of bin values between the bin centres, with its slope; where a
  // corner is empty, the mean of the others with no slope. False where all are empty.
  bool interpolate(const std::vector<double>& values, bool shifted, const Eigen::Vector3d& x,
                   double& value, std::array<double, 2>& slope) const {
    std::array<int, 2> cell{0, 0};
    std::array<double, 2> f{0.0, 0.0};
    for (int a = 0; a < in_.dimension - 1; ++a) {
      const double u = (x[axis_[a]] - origin_[a]) / width_[a] - 0.5;
      cell[a] = static_cast<int>(std::floor(u));
      f[a] = u - cell[a];
    }
    const int corners1 = in_.dimension == 3 ? 2 : 1;
    std::array<double, 4> node{kEmpty, kEmpty, kEmpty, kEmpty};
    double sum = 0.0;
    int defined = 0;
    for (int c1 = 0; c1 < corners1; ++c1) {
      for (int c0 = 0; c0 < 2; ++c0) {
        const double v = lookup(values, cell[0] + c0, cell[1] + c1, shifted);
        node[2 * c1 + c0] = v;
        if (v != kEmpty) {
          sum += v;
          ++defined;
        }
      }
    }
    slope = {0.0, 0.0};
    if (defined == 0) return false;
    value = sum / defined;
    if (defined < 2 * corners1) return true;
    if (in_.dimension == 2) {
      value = (1.0 - f[0]) * node[0] + f[0] * node[1];
      slope[0] = (node[1] - node[0]) / width_[0];
    } else {
      const double e0 = (1.0 - f[0]) * node[0] + f[0] * node[1];
      const double e1 = (1.0 - f[0]) * node[2] + f[0] * node[3];
      value = (1.0 - f[1]) * e0 + f[1] * e1;
      slope[0] = ((1.0 - f[1]) * (node[1] - node[0]) + f[1] * (node[3] - node[2])) / width_[0];
      slope[1] = (e1 - e0) / width_[1];
    }
    return true;
  }
  // The value of bin (b0, b1), wrapped along a periodic axis 0 (a height `shifted` by the drop
  // per period); kEmpty outside the bins.
  double lookup(const std::vector<double>& values, int b0, int b1, bool shifted = true) const {
    if (b1 < 0 || b1 >= bins_[1]) return kEmpty;
    double shift = 0.0;
    if (periodic_) {
      while (b0 < 0) {
        b0 += bins_[0];
        shift += drop_;  // one period upstream: higher
      }
      while (b0 >= bins_[0]) {
        b0 -= bins_[0];
        shift -= drop_;
      }
    } else if (b0 < 0 || b0 >= bins_[0]) {
      return kEmpty;
    }
    const double v = values[index(b0, b1)];
    return v == kEmpty ? kEmpty : v + (shifted ? shift : 0.0);
  }

  const BackgroundInput& in_;
  int up_ = 0;
  double g_up_ = 0.0, sign_ = 1.0, drop_ = 0.0;
  std::array<int, 2> axis_{0, 0};
  bool periodic_ = false;
  std::array<double, 2> origin_{0.0, 0.0}, width_{1.0, 1.0};
  std::array<int, 2> bins_{1, 1};
  std::vector<double> smoothed_, trust_;
};

}  // namespace

void hydrostatic_background(const BackgroundInput& in, BackgroundField& out) {
  const auto& kinds = *in.kinds;
  const int n = static_cast<int>(kinds.size());
  out.pressure.assign(n, 0.0);
  out.gradient.assign(n, Eigen::Vector3d::Zero());
  out.trust.assign(n, 0.0);
  out.fade.assign(n, 0.0);
  if (n == 0 || in.gravity.squaredNorm() == 0.0) return;
  const SurfaceHeights surface(in);
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    if (carries_pressure(kinds[i]))
      surface.background((*in.positions)[i], out.pressure[i], out.gradient[i], out.trust[i],
                         out.fade[i]);
  }
}

}  // namespace cosim::mps
