// Unit tests of the hydrostatic background of the pressure gradient
// (hydrostatic_background.hpp, issue 16): the background of a flat layer, of a sloping surface
// in 2D and 3D, across a periodic seam with a drop, nothing far from the water, and none in a jet
// over air.
#include <gtest/gtest.h>

#include <cmath>

#include "cosim/fluid_mps/hydrostatic_background.hpp"

using namespace cosim::mps;

namespace {

constexpr double kRho = 1000.0, kG = 9.81, kL0 = 0.01;
constexpr double kHalf = 0.5 * kL0;  // the surface lies half a spacing above the top particles

// Columns of fluid particles whose top particle sits at eta(x, z) exactly, down to the bed (the
// lowest at most a spacing above it), over two rows of wall and one of dummies (2D: one layer
// in z).
struct Layer {
  std::vector<Eigen::Vector3d> positions;
  std::vector<ParticleKind> kinds;
  PeriodicBoundary periodic;
  BackgroundInput input(int dimension) const {
    BackgroundInput in;
    in.dimension = dimension;
    in.gravity = dimension == 3 ? Eigen::Vector3d(0, 0, -kG) : Eigen::Vector3d(0, -kG, 0);
    in.density = kRho;
    in.particle_spacing = kL0;
    in.positions = &positions;
    in.kinds = &kinds;
    in.periodic = &periodic;
    return in;
  }
};

template <class Surface>
Layer layer(int dimension, int columns, Surface&& eta) {
  Layer l;
  const int layers = dimension == 3 ? columns : 1;
  const int up = dimension == 3 ? 2 : 1;
  for (int c1 = 0; c1 < layers; ++c1) {
    for (int c0 = 0; c0 < columns; ++c0) {
      Eigen::Vector3d base = Eigen::Vector3d::Zero();
      base.x() = (c0 + 0.5) * kL0;
      if (dimension == 3) base.y() = (c1 + 0.5) * kL0;
      const double top = eta(base.x(), base.y());
      const int rows = static_cast<int>(std::floor(top / kL0 + 1e-9)) + 1;
      for (int r = -3; r < rows; ++r) {
        Eigen::Vector3d x = base;
        x[up] = r < 0 ? (r + 0.5) * kL0 : top - (rows - 1 - r) * kL0;
        l.positions.push_back(x);
        l.kinds.push_back(r < -2  ? ParticleKind::dummy
                          : r < 0 ? ParticleKind::wall
                                  : ParticleKind::fluid);
      }
    }
  }
  return l;
}

// The background of a column whose top particle is at `top`, and no background, at x.
void expect_column(double p, double top, const Eigen::Vector3d& x) {
  EXPECT_NEAR(p, kRho * kG * (top + kHalf - x.y()), 1e-9) << x.transpose();
}
// No column above x (air, or no water near): no background and no trust.
void expect_no_column(double p, const Eigen::Vector3d& gradient, double trust,
                      const Eigen::Vector3d& x) {
  EXPECT_EQ(p, 0.0) << x.transpose();
  EXPECT_EQ(gradient.norm(), 0.0) << x.transpose();
  EXPECT_EQ(trust, 0.0) << x.transpose();
}

BackgroundField background(const BackgroundInput& in) {
  BackgroundField field;
  hydrostatic_background(in, field);
  return field;
}

}  // namespace

TEST(MpsHydrostaticBackground, FlatLayerIsHydrostaticBelowTheTopParticles) {
  const Layer l = layer(2, 20, [](double, double) { return 0.1; });
  const auto [p, g, s, fade] = background(l.input(2));
  for (std::size_t i = 0; i < l.positions.size(); ++i) {
    if (l.kinds[i] == ParticleKind::dummy) {
      EXPECT_EQ(p[i], 0.0);
      EXPECT_EQ(g[i].norm(), 0.0);
      continue;
    }
    const double depth = 0.1 + kHalf - l.positions[i].y();
    EXPECT_NEAR(p[i], depth > 0.0 ? kRho * kG * depth : 0.0, 1e-9) << i;
    EXPECT_EQ(s[i], depth > 0.0 ? 1.0 : 0.0) << i;
    if (depth > 0.0) {
      EXPECT_NEAR(g[i].x(), 0.0, 1e-9);
      EXPECT_NEAR(g[i].y(), -kRho * kG, 1e-9);
    }
  }
}

TEST(MpsHydrostaticBackground, SlopingSurfaceGivesItsSlopeInTheInterior) {
  const double slope = 0.05;
  auto eta = [&](double x, double) { return 0.1 - slope * x; };
  const Layer l = layer(2, 30, eta);
  const auto [p, g, s, fade] = background(l.input(2));
  int checked = 0;
  for (std::size_t i = 0; i < l.positions.size(); ++i) {
    const Eigen::Vector3d& x = l.positions[i];
    // Two bins of smoothing, and half a bin of interpolation, from either end.
    if (l.kinds[i] != ParticleKind::fluid || x.x() < 3.0 * kL0 || x.x() > 27.0 * kL0) continue;
    EXPECT_NEAR(p[i], kRho * kG * (eta(x.x(), 0.0) + kHalf - x.y()), 1e-6) << i;
    EXPECT_NEAR(g[i].x(), -kRho * kG * slope, 1e-6) << i;
    EXPECT_NEAR(g[i].y(), -kRho * kG, 1e-9) << i;
    ++checked;
  }
  EXPECT_GT(checked, 100);
}

TEST(MpsHydrostaticBackground, PeriodicSeamKeepsTheSlopeOfADroppingChannel) {
  const int columns = 20;
  const double length = columns * kL0, drop = 0.004;
  auto eta = [&](double x, double) { return 0.1 - drop * x / length; };
  Layer l = layer(2, columns, eta);
  l.periodic.enabled = true;
  l.periodic.x_min = 0.0;
  l.periodic.x_max = length;
  l.periodic.drop = drop;
  const auto [p, g, s, fade] = background(l.input(2));
  for (std::size_t i = 0; i < l.positions.size(); ++i) {
    if (l.kinds[i] != ParticleKind::fluid) continue;
    // Everywhere, the seam included: the bins wrap with the drop.
    EXPECT_NEAR(g[i].x(), -kRho * kG * drop / length, 1e-6) << l.positions[i].x();
    const double expected_eta =
        l.positions[i].x() < 0.5 * kL0
            ? eta(0.5 * kL0, 0.0) + (0.5 * kL0 - l.positions[i].x()) * drop / length
            : eta(l.positions[i].x(), 0.0);
    EXPECT_NEAR(p[i], kRho * kG * (expected_eta + kHalf - l.positions[i].y()), 1e-6);
  }
}

namespace {

// The background of every fluid particle of a 3D layer 12 columns wide, three columns or more
// from its sides: that of the plane eta = eta0 + sx x + sy y.
void expect_plane(const Layer& l, double eta0, double sx, double sy) {
  const auto [p, g, s, fade] = background(l.input(3));
  int checked = 0;
  for (std::size_t i = 0; i < l.positions.size(); ++i) {
    const Eigen::Vector3d& x = l.positions[i];
    const bool interior =
        x.x() > 3.0 * kL0 && x.x() < 9.0 * kL0 && x.y() > 3.0 * kL0 && x.y() < 9.0 * kL0;
    if (l.kinds[i] != ParticleKind::fluid || !interior) continue;
    const double eta = eta0 + sx * x.x() + sy * x.y();
    EXPECT_NEAR(p[i], kRho * kG * (eta + kHalf - x.z()), 1e-6) << x.transpose();
    EXPECT_NEAR(g[i].x(), kRho * kG * sx, 1e-6) << x.transpose();
    EXPECT_NEAR(g[i].y(), kRho * kG * sy, 1e-6) << x.transpose();
    EXPECT_NEAR(g[i].z(), -kRho * kG, 1e-9) << x.transpose();
    ++checked;
  }
  EXPECT_GT(checked, 100);
}

}  // namespace

TEST(MpsHydrostaticBackground, ThreeDimensionalPlane) {
  const double sx = 0.03, sy = -0.02;
  expect_plane(layer(3, 12, [&](double x, double y) { return 0.08 + sx * x + sy * y; }), 0.08, sx,
               sy);
}

// A flat 3D layer whose top particle is missing from every third column along x and every
// second along y (as bins of l0 x l0 miss the top layer of an fcc lattice, 0.79 particles to the
// bin): those columns' own top lies a spacing lower, and are left out of the surface's mean, so
// the surface stays flat and the background has no sideways gradient.
TEST(MpsHydrostaticBackground, ThreeDimensionalColumnsBelowTheTopLayerLeaveTheSurfaceFlat) {
  const double eta = 0.08;
  Layer full = layer(3, 12, [&](double, double) { return eta; });
  Layer l;
  l.periodic = full.periodic;
  for (std::size_t i = 0; i < full.positions.size(); ++i) {
    const Eigen::Vector3d& x = full.positions[i];
    const int c0 = static_cast<int>(x.x() / kL0), c1 = static_cast<int>(x.y() / kL0);
    const bool top = std::abs(x.z() - eta) < 1e-9;
    if (top && c0 % 3 == 1 && c1 % 2 == 0) continue;
    l.positions.push_back(x);
    l.kinds.push_back(full.kinds[i]);
  }
  ASSERT_LT(l.positions.size(), full.positions.size());
  expect_plane(l, eta, 0.0, 0.0);
}

TEST(MpsHydrostaticBackground, NoBackgroundFarFromTheWater) {
  // Water over the first 10 columns only; the bed goes on for 20 more.
  Layer l = layer(2, 30, [](double, double) { return 0.05; });
  for (std::size_t i = 0; i < l.positions.size(); ++i) {
    if (l.kinds[i] == ParticleKind::fluid && l.positions[i].x() > 10.0 * kL0)
      l.kinds[i] = ParticleKind::inactive;
  }
  const auto [p, g, s, fade] = background(l.input(2));
  for (std::size_t i = 0; i < l.positions.size(); ++i) {
    if (l.kinds[i] != ParticleKind::wall) continue;
    const double x = l.positions[i].x();
    if (x < 10.0 * kL0) {
      EXPECT_GT(p[i], 0.0);
    } else if (x > 13.0 * kL0) {  // beyond two bins of smoothing and one of interpolation
      EXPECT_EQ(p[i], 0.0) << x;
      EXPECT_EQ(g[i].norm(), 0.0);
    }
  }
}

TEST(MpsHydrostaticBackground, FadesInBelowTheSurfaceAndTrustsOnlyGentleSurfaces) {
  // A deep block (eta = 0.2 m) over the first 15 columns, a layer 3 cm deep after it: a step of
  // 17 cm, far more than 2 delta.
  const double delta = 0.04;
  const Layer l = layer(2, 40, [](double x, double) { return x < 0.15 ? 0.2 : 0.03; });
  BackgroundInput in = l.input(2);
  in.taper_depth = delta;
  const auto [p, g, s, fade] = background(in);
  int deep_block = 0, near_step = 0;
  for (std::size_t i = 0; i < l.positions.size(); ++i) {
    if (l.kinds[i] != ParticleKind::fluid) continue;
    const Eigen::Vector3d& x = l.positions[i];
    // S looks 2 + delta / l0 = 6 bins either way: the step is out of sight below x = 0.085 m.
    if (x.x() < 0.08) {  // gentle: S = 1, f faded in over delta
      const double d = 0.2 + kHalf - x.y();
      const double f = d < delta ? 0.5 * d * d / delta : d - 0.5 * delta;
      EXPECT_NEAR(p[i], kRho * kG * f, 1e-6) << x.transpose();
      EXPECT_NEAR(g[i].y(), -kRho * kG * std::min(d / delta, 1.0), 1e-6);
      EXPECT_NEAR(g[i].x(), 0.0, 1e-6);
      ++deep_block;
      EXPECT_EQ(s[i], 1.0) << x.transpose();
    } else if (x.x() > 0.10 && x.x() < 0.20) {  // the window spans the step's 17 cm: S = 0
      // The column's field is whole (the step weighs it by S; no gradient of S enters it).
      EXPECT_EQ(s[i], 0.0) << x.transpose();
      if (x.y() < 0.02) {
        EXPECT_GT(p[i], 0.0) << x.transpose();
      }
      ++near_step;
    }
  }
  EXPECT_GT(deep_block, 100);
  EXPECT_GT(near_step, 40);
}

// background_fade: blend keeps p_b linear (the operator sees no curved field in the surface
// layer) and moves the fade onto the trust: S min(d / delta, 1), the full repulsion's fade 1; the
// trust's reach stays that of the operator (taper_depth) when the fade depth differs.
TEST(MpsHydrostaticBackground, BlendFadeKeepsTheBackgroundLinearAndFadesTheTrust) {
  const double delta = 0.04, top = 0.2 + kHalf;
  const Layer l = layer(2, 40, [](double x, double) { return x < 0.15 ? 0.2 : 0.03; });
  for (const double fade_depth : {0.0, 2.0 * delta}) {
    BackgroundInput in = l.input(2);
    in.taper_depth = delta;
    in.fade_depth = fade_depth;
    in.blend_fade = true;
    const double depth_of_fade = fade_depth > 0.0 ? fade_depth : delta;
    const auto [p, g, s, fade] = background(in);
    int checked = 0, faded = 0;
    for (std::size_t i = 0; i < l.positions.size(); ++i) {
      if (l.kinds[i] != ParticleKind::fluid) continue;
      const Eigen::Vector3d& x = l.positions[i];
      if (x.x() < 0.08) {  // the gentle part, as in the taper's test: the column's S is 1
        const double d = top - x.y();
        EXPECT_NEAR(p[i], kRho * kG * d, 1e-6) << x.transpose();
        EXPECT_NEAR(g[i].y(), -kRho * kG, 1e-6);
        EXPECT_NEAR(g[i].x(), 0.0, 1e-6);
        EXPECT_NEAR(s[i], std::min(d / depth_of_fade, 1.0), 1e-12) << x.transpose();
        EXPECT_EQ(fade[i], 1.0);
        faded += d < depth_of_fade;
        ++checked;
      } else if (x.x() > 0.10 && x.x() < 0.20) {
        EXPECT_EQ(s[i], 0.0) << x.transpose();  // the step is still seen over the operator's reach
      }
    }
    EXPECT_GT(checked, 100);
    EXPECT_GE(faded, fade_depth > 0.0 ? 7 * 8 : 3 * 8) << "rows of 8 columns inside the fade";
  }
}

TEST(MpsHydrostaticBackground, WaterAboveAnAirGapIsNotPartOfTheColumn) {
  // A pool 5 cm deep, and a jet 3 cm thick flying 5 cm above it over columns 8-15 (a nappe over
  // the pool it falls into): the pool's background is that of its own surface, the jet has none.
  const double pool = 0.05;
  Layer l = layer(2, 24, [&](double, double) { return pool; });
  for (int c = 8; c < 16; ++c) {
    for (int r = 0; r < 3; ++r) {
      l.positions.emplace_back((c + 0.5) * kL0, pool + 0.06 + r * kL0, 0.0);
      l.kinds.push_back(ParticleKind::fluid);
    }
  }
  const auto [p, g, s, fade] = background(l.input(2));
  int pool_checked = 0, jet_checked = 0;
  for (std::size_t i = 0; i < l.positions.size(); ++i) {
    if (l.kinds[i] != ParticleKind::fluid) continue;
    const Eigen::Vector3d& x = l.positions[i];
    if (x.y() < pool + kHalf) {
      expect_column(p[i], pool, x);
      EXPECT_NEAR(g[i].x(), 0.0, 1e-9) << x.transpose();
      ++pool_checked;
    } else {
      expect_no_column(p[i], g[i], s[i], x);
      ++jet_checked;
    }
  }
  EXPECT_EQ(pool_checked, 24 * 6);
  EXPECT_EQ(jet_checked, 8 * 3);
}

TEST(MpsHydrostaticBackground, NoBackgroundNearWaterThatNoWallHoldsUp) {
  // A layer 3 cm deep whose bed ends at x = 0.4 m; past it the same water has nothing below
  // (a nappe leaving a brink): no trust within three depths of the unsupported columns.
  Layer l = layer(2, 60, [](double, double) { return 0.03; });
  for (std::size_t i = 0; i < l.positions.size(); ++i) {
    if (l.kinds[i] != ParticleKind::fluid && l.positions[i].x() > 0.4)
      l.kinds[i] = ParticleKind::inactive;
  }
  const auto [p, g, s, fade] = background(l.input(2));
  int upstream = 0, past = 0;
  for (std::size_t i = 0; i < l.positions.size(); ++i) {
    if (l.kinds[i] != ParticleKind::fluid) continue;
    const Eigen::Vector3d& x = l.positions[i];
    // Columns 41 and up have no wall in their bin or the one before (column 40 has column 39's);
    // three depths of 3.5 cm reach 11 bins from column 41: bins 30 and up have S = 0, bin 29's
    // centre is the last interpolated from trusted bins only.
    if (x.x() < 29.5 * kL0) {
      expect_column(p[i], 0.03, x);
      EXPECT_EQ(s[i], 1.0) << x.transpose();
      ++upstream;
    } else if (x.x() > 30.5 * kL0) {
      EXPECT_EQ(s[i], 0.0) << x.transpose();
      ++past;
    }
  }
  EXPECT_EQ(upstream, 29 * 4);
  EXPECT_EQ(past, 29 * 4);
}

TEST(MpsHydrostaticBackground, NoTrustNearAStepInTheBed) {
  // A flat surface at 0.1 m over a bed that rises 5 cm at x = 0.4 m (the top of a partition, a
  // crest): the water flows over the step, so S is 0 within three depths of the water over it
  // (5.5 cm: 17 bins), far beyond the operator's reach, and 1 far from it.
  const double delta = 0.02;
  Layer l = layer(2, 80, [](double, double) { return 0.1; });
  for (std::size_t i = 0; i < l.positions.size(); ++i) {
    const Eigen::Vector3d& x = l.positions[i];
    if (x.x() > 0.4 && x.y() < 0.05 && l.kinds[i] == ParticleKind::fluid)
      l.kinds[i] = ParticleKind::wall;  // the raised bed
  }
  BackgroundInput in = l.input(2);
  in.taper_depth = delta;
  const auto [p, g, s, fade] = background(in);
  // The raised side's first bin (40) is the feature: bins 23 to 57 have S = 0.
  int far = 0, near = 0;
  for (std::size_t i = 0; i < l.positions.size(); ++i) {
    if (l.kinds[i] != ParticleKind::fluid) continue;
    const double x = l.positions[i].x();
    if (x < 0.2 || x > 0.6) {
      EXPECT_EQ(s[i], 1.0) << x;
      ++far;
    } else if (x > 0.25 && x < 0.55) {
      EXPECT_EQ(s[i], 0.0) << x;
      ++near;
    }
  }
  EXPECT_GT(far, 100);
  EXPECT_GT(near, 10);
}

TEST(MpsHydrostaticBackground, AGapInOneBinWithWaterBesideItIsNotAir) {
  // Disordered water can leave one l0 bin without particles over 4 l0 of its height while its
  // neighbours fill that height: the column is still one layer up to its top particle.
  Layer l = layer(2, 20, [](double, double) { return 0.1; });
  for (std::size_t i = 0; i < l.positions.size(); ++i) {
    const Eigen::Vector3d& x = l.positions[i];
    if (l.kinds[i] == ParticleKind::fluid && x.x() > 0.1 && x.x() < 0.11 && x.y() > 0.025 &&
        x.y() < 0.075)
      l.kinds[i] = ParticleKind::inactive;  // column 10: no particle from 0.03 to 0.07 m
  }
  const auto [p, g, s, fade] = background(l.input(2));
  int below_gap = 0;
  for (std::size_t i = 0; i < l.positions.size(); ++i) {
    const Eigen::Vector3d& x = l.positions[i];
    if (l.kinds[i] != ParticleKind::fluid || x.x() < 0.1 || x.x() > 0.11 || x.y() > 0.025) continue;
    expect_column(p[i], 0.1, x);
    ++below_gap;
  }
  EXPECT_EQ(below_gap, 3);
}
