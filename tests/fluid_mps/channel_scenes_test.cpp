// The open channel's outlet (boundaries.hpp, ChannelOutlet; seed 000 section 4): a bed level in
// the world and a 1:1 adverse slope beyond the channel, with wall particles along both and a free
// overfall at the crest.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "cosim/fluid_mps/boundaries.hpp"
#include "cosim/fluid_mps/fluid_system.hpp"
#include "quiet_settings.hpp"

using namespace cosim::mps;

namespace {

// Gravity tilted by a bed slope sin(theta) = 0.01, as the world of the honami scene gives it.
MpsParameters tilted(double l0, double sine) {
  MpsParameters p = cosim::mps::testing::quiet_parameters(l0);
  p.gravity = 9.81 * Eigen::Vector3d(sine, -std::sqrt(1.0 - sine * sine), 0.0);
  return p;
}

double nearest(const ParticleSet& set, ParticleKind kind, const Eigen::Vector3d& point) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < set.positions.size(); ++i) {
    if (set.kinds[i] == kind) best = std::min(best, (set.positions[i] - point).norm());
  }
  return best;
}

}  // namespace

// The crest lies where the level bed and the 1:1 slope put it, wall particles line the level bed,
// the slope and the crest's vertical face within a particle spacing, no water starts inside the
// solid or beyond the crest, and the outflow line lies beyond the crest.
TEST(MpsChannelOutlet, LevelBedAndAdverseSlopeAreBuilt) {
  const double l0 = 0.05, sine = 0.01, length = 3.0, depth = 0.6;
  const double cosine = std::sqrt(1.0 - sine * sine);
  MpsParameters p = tilted(l0, sine);
  OpenBoundarySettings settings;
  const ChannelOutlet outlet{1.0, 0.5};
  const ParticleSet set = open_channel(p, settings, length, depth, 1.5, 4, 100, 2, 2, 0.0, outlet);
  // Level in the world: along (cos, sin) of the channel frame; the slope along that plus the
  // world's vertical (-sin, cos), 0.5 m up.
  const Eigen::Vector3d a(length, 0.0, 0.0);
  const Eigen::Vector3d b = a + 1.0 * Eigen::Vector3d(cosine, sine, 0.0);
  const Eigen::Vector3d c = b + 0.5 * Eigen::Vector3d(cosine - sine, sine + cosine, 0.0);
  EXPECT_LT((outlet_crest(p, length, outlet) - c).norm(), 1e-12);
  EXPECT_NEAR(b.y(), 0.01, 1e-4);  // the level bed rises 1 cm against the 1/100 channel bed
  // Wall particles along the bed line: a cell is solid when its centre lies under the line, so
  // the line passes less than one cell above the centre of the solid cell below it, and a point
  // of the line is within sqrt(0.5^2 + 1^2) l0 = 1.12 l0 of a wall centre.
  const double reach = std::sqrt(1.25) * l0;
  for (int k = 0; k <= 20; ++k) {
    const double s = k / 20.0;
    EXPECT_LT(nearest(set, ParticleKind::wall, a + s * (b - a)), reach) << "level bed " << s;
    EXPECT_LT(nearest(set, ParticleKind::wall, b + s * (c - b)), reach) << "slope " << s;
  }
  // The crest's downstream face, down to the bed's dummy rows.
  for (double y = c.y() - l0; y > -2.0 * l0; y -= l0) {
    EXPECT_LT(nearest(set, ParticleKind::wall, Eigen::Vector3d(c.x(), y, 0.0)), reach)
        << "face at y = " << y;
  }
  // The slope carries walls backed by dummies, as every face water touches.
  EXPECT_LT(nearest(set, ParticleKind::dummy, 0.5 * (b + c) + Eigen::Vector3d(2 * l0, -2 * l0, 0)),
            1.5 * l0);
  int fluid_over_outlet = 0;
  for (std::size_t i = 0; i < set.positions.size(); ++i) {
    const Eigen::Vector3d& r = set.positions[i];
    if (set.kinds[i] == ParticleKind::wall || set.kinds[i] == ParticleKind::dummy) {
      EXPECT_LE(r.x(), c.x() + 1e-12) << "no solid beyond the crest";
    }
    if (set.kinds[i] != ParticleKind::fluid || r.x() < length) continue;
    ++fluid_over_outlet;
    EXPECT_LT(r.x(), c.x());
    EXPECT_LT(r.y(), depth);
    // Above the bed line: level bed, then the slope.
    const double surface = r.x() <= b.x()
                               ? (r.x() - a.x()) * sine / cosine
                               : b.y() + (r.x() - b.x()) * (c.y() - b.y()) / (c.x() - b.x());
    EXPECT_GT(r.y(), surface) << "fluid at x = " << r.x();
  }
  EXPECT_GT(fluid_over_outlet, 0);
  EXPECT_GT(settings.outflow_x, c.x());
}

// Without an outlet the channel is the one it always was: the same particles.
TEST(MpsChannelOutlet, NoOutletKeepsTheFreeOverfall) {
  MpsParameters p = tilted(0.05, 0.01), q = p;
  OpenBoundarySettings s1, s2;
  const ParticleSet plain = open_channel(p, s1, 3.0, 0.6, 1.5, 4, 100, 2, 2, 0.0);
  const ParticleSet empty = open_channel(q, s2, 3.0, 0.6, 1.5, 4, 100, 2, 2, 0.0, ChannelOutlet{});
  ASSERT_EQ(plain.positions.size(), empty.positions.size());
  for (std::size_t i = 0; i < plain.positions.size(); ++i) {
    EXPECT_EQ(plain.positions[i], empty.positions[i]);
    EXPECT_EQ(plain.kinds[i], empty.kinds[i]);
  }
  EXPECT_EQ(s1.outflow_x, s2.outflow_x);
  EXPECT_EQ(outlet_crest(p, 3.0, ChannelOutlet{}), Eigen::Vector3d(3.0, 0.0, 0.0));
}

// Water released against the slope stays on its side of the wall: after 0.3 s no fluid particle
// lies more than half a spacing under the outlet's bed line.
TEST(MpsChannelOutlet, SlopeHoldsTheWater) {
  const double l0 = 0.05, sine = 0.01, length = 1.0;
  MpsParameters p = tilted(l0, sine);
  OpenBoundarySettings settings;
  const ChannelOutlet outlet{0.5, 0.4};
  FluidSystem system(p, open_channel(p, settings, length, 0.3, 0.8, 4, 50, 2, 2, 0.0, outlet));
  while (system.time() < 0.3) system.step(std::min(2e-3, system.stable_dt()));
  const double cosine = std::sqrt(1.0 - sine * sine);
  const Eigen::Vector3d b = Eigen::Vector3d(length, 0, 0) + 0.5 * Eigen::Vector3d(cosine, sine, 0);
  const Eigen::Vector3d c = outlet_crest(p, length, outlet);
  int checked = 0;
  for (int i = 0; i < system.particle_count(); ++i) {
    const Eigen::Vector3d& r = system.positions()[i];
    if (system.kinds()[i] != ParticleKind::fluid || r.x() < b.x() || r.x() > c.x()) continue;
    const double surface = b.y() + (r.x() - b.x()) * (c.y() - b.y()) / (c.x() - b.x());
    EXPECT_GT(r.y(), surface - 0.5 * l0) << "particle " << i << " at x = " << r.x();
    ++checked;
  }
  EXPECT_GT(checked, 0);
}
