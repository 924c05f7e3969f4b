// Unit tests of the pressure-gradient models and particle shifting (pressure_gradient.hpp,
// issue 16): antisymmetry of the conservative forms, exactness of the corrected form for linear
// fields, the smooth (normal-only) wall, the direction of the shift, and a closed momentum balance.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <map>
#include <random>

#include "cosim/fluid_mps/boundaries.hpp"
#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/hydrostatic_background.hpp"
#include "cosim/fluid_mps/kernels.hpp"
#include "cosim/fluid_mps/neighbour_grid.hpp"
#include "cosim/fluid_mps/operators.hpp"
#include "cosim/fluid_mps/pressure_gradient.hpp"
#include "quiet_settings.hpp"

using namespace cosim::mps;

namespace {

using Form = MpsParameters::GradientForm;

// A block of particles `columns` x `rows` (x `rows` deep in 3D) of spacing l0 above two rows of
// wall particles and one of dummies, every fluid particle moved randomly by up to `jitter` l0.
struct Block {
  std::vector<Eigen::Vector3d> positions;
  std::vector<ParticleKind> kinds;
  std::vector<double> pressure;
  NeighbourList list;
  PeriodicBoundary periodic;
  GradientInput input(int dimension, double radius_over_l0, double l0) {
    GradientInput in;
    in.dimension = dimension;
    in.radius = radius_over_l0 * l0;
    in.n0 = lattice_sums(dimension, radius_over_l0).n0;
    in.neighbours = &list;
    in.positions = &positions;
    in.kinds = &kinds;
    in.pressure = &pressure;
    in.periodic = &periodic;
    return in;
  }
};

Block block(int dimension, int columns, int rows, double l0, double jitter, double radius,
            unsigned seed) {
  Block b;
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> shake(-jitter * l0, jitter * l0);
  const int layers = dimension == 3 ? columns : 1;
  for (int z = 0; z < layers; ++z) {
    for (int y = -3; y < rows; ++y) {
      for (int x = 0; x < columns; ++x) {
        Eigen::Vector3d r(x * l0, y * l0, dimension == 3 ? z * l0 : 0.0);
        ParticleKind kind = y < -2  ? ParticleKind::dummy
                            : y < 0 ? ParticleKind::wall
                                    : ParticleKind::fluid;
        if (kind == ParticleKind::fluid) {
          r.x() += shake(random);
          r.y() += shake(random);
          if (dimension == 3) r.z() += shake(random);
        }
        b.positions.push_back(r);
        b.kinds.push_back(kind);
      }
    }
  }
  NeighbourGrid grid(dimension, bounding_box(b.positions, dimension, radius), radius);
  grid.build(b.positions);
  b.list = grid.neighbours(b.positions, radius);
  return b;
}

// Sum over fluid particles of their fluid-fluid pressure force (in units of -V d/n0) and of the
// magnitudes, for the relative round-off bound.
std::pair<Eigen::Vector3d, double> fluid_fluid_sum(Form form, Block& b, int dimension,
                                                   double radius_over_l0, double l0) {
  std::vector<Eigen::Vector3d> gradient, wall;
  std::vector<double> minimum;
  pressure_gradients(form, b.input(dimension, radius_over_l0, l0), gradient, wall, minimum);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double magnitude = 0.0;
  for (std::size_t i = 0; i < b.kinds.size(); ++i) {
    if (b.kinds[i] != ParticleKind::fluid) continue;
    sum += gradient[i] - wall[i];
    magnitude += (gradient[i] - wall[i]).norm();
  }
  return {sum, magnitude};
}

}  // namespace

// Between fluid particles the symmetric forms are pairwise equal and opposite: on a disordered
// block with random pressures the fluid-fluid forces sum to round-off. The minimum form does not
// (the momentum the rigid_canopy balance missed).
TEST(MpsPressureGradient, ConservativeFormsCancelBetweenFluidPairs) {
  const double l0 = 0.01;
  for (const int dimension : {2, 3}) {
    const double radius_over_l0 = dimension == 2 ? 4.0 : 2.1;
    Block b = block(dimension, dimension == 2 ? 20 : 8, dimension == 2 ? 12 : 6, l0, 0.2,
                    radius_over_l0 * l0, 7);
    std::mt19937 random(11);
    std::uniform_real_distribution<double> pressure(0.0, 1000.0);
    for (std::size_t i = 0; i < b.kinds.size(); ++i) b.pressure.push_back(pressure(random));
    for (const Form form : {Form::symmetric, Form::symmetric_normal_wall}) {
      const auto [sum, magnitude] = fluid_fluid_sum(form, b, dimension, radius_over_l0, l0);
      EXPECT_LT(sum.norm(), 1e-13 * magnitude) << "dimension " << dimension;
      EXPECT_GT(magnitude, 0.0);
    }
    const auto [sum, magnitude] = fluid_fluid_sum(Form::minimum, b, dimension, radius_over_l0, l0);
    EXPECT_GT(sum.norm(), 1e-3 * magnitude) << "dimension " << dimension;
  }
}

// The correction matrix makes the gradient of a linear field exact on a disordered arrangement,
// in 2D and 3D, wherever the neighbourhood is full enough to invert (everywhere in this block,
// which includes the wall rows beneath the fluid).
TEST(MpsPressureGradient, CorrectedGradientOfLinearFieldIsExact) {
  const double l0 = 0.01;
  for (const int dimension : {2, 3}) {
    const double radius_over_l0 = dimension == 2 ? 3.1 : 2.1;
    Block b = block(dimension, dimension == 2 ? 16 : 8, dimension == 2 ? 10 : 6, l0, 0.3,
                    radius_over_l0 * l0, 3);
    const Eigen::Vector3d slope = dimension == 2 ? Eigen::Vector3d(120.0, -9810.0, 0.0)
                                                 : Eigen::Vector3d(120.0, -9810.0, 35.0);
    for (const auto& r : b.positions) b.pressure.push_back(500.0 + slope.dot(r));
    const GradientInput in = b.input(dimension, radius_over_l0, l0);
    const std::vector<Eigen::Vector3d> g = corrected_gradient(in, b.pressure, b.pressure);
    // The uncorrected MPS gradient of the same field, for contrast.
    const std::vector<Eigen::Vector3d> plain =
        gradient(dimension, b.positions, b.pressure, b.list, in.radius, in.n0);
    // Away from the block's open sides and top, where the neighbourhood is full enough.
    const int columns = dimension == 2 ? 16 : 8, rows = dimension == 2 ? 10 : 6;
    auto inside = [&](const Eigen::Vector3d& r) {
      const double margin = in.radius;
      const double side = (columns - 1) * l0 - margin;
      return r.x() > margin && r.x() < side && r.y() < (rows - 1) * l0 - margin &&
             (dimension == 2 || (r.z() > margin && r.z() < side));
    };
    double worst = 0.0, worst_plain = 0.0;
    for (std::size_t i = 0; i < b.kinds.size(); ++i) {
      if (b.kinds[i] != ParticleKind::fluid || !inside(b.positions[i])) continue;
      worst = std::max(worst, (g[i] - slope).norm() / slope.norm());
      worst_plain = std::max(worst_plain, (plain[i] - slope).norm() / slope.norm());
    }
    EXPECT_LT(worst, 1e-10) << "dimension " << dimension;
    EXPECT_GT(worst_plain, 1e-2) << "dimension " << dimension;
  }
}

// On a full lattice the corrected form as the step uses it (the minimum p^_i as the reference,
// which keeps the pair forces repulsive) is the exact gradient: the p^_i part sums to zero there.
TEST(MpsPressureGradient, CorrectedFormOnFullLatticeIsExact) {
  const double l0 = 0.01, radius_over_l0 = 4.0;
  Block b = block(2, 24, 24, l0, 0.0, radius_over_l0 * l0, 1);
  const Eigen::Vector3d slope(40.0, -9810.0, 0.0);
  for (const auto& r : b.positions) b.pressure.push_back(3000.0 + slope.dot(r));
  std::vector<Eigen::Vector3d> g, wall;
  std::vector<double> minimum;
  const GradientInput in = b.input(2, radius_over_l0, l0);
  pressure_gradients(Form::corrected, in, g, wall, minimum);
  const int centre = (3 + 12) * 24 + 12;  // row 12 of the fluid, column 12
  ASSERT_EQ(b.kinds[centre], ParticleKind::fluid);
  EXPECT_LT((gradient_factor(2, in.n0) * g[centre] - slope).norm(), 1e-9 * slope.norm());
}

// corrected_interior: where a particle or a fluid neighbour within the radius is on the free
// surface (no pressure unknown) it is the minimum form; with a full neighbourhood it is the
// corrected form, which differs from the minimum form on a disordered arrangement.
TEST(MpsPressureGradient, CorrectedInteriorCorrectsOffTheSurfaceOnly) {
  const double l0 = 0.01, radius_over_l0 = 3.1;
  const int columns = 16, rows = 14;
  Block b = block(2, columns, rows, l0, 0.2, radius_over_l0 * l0, 5);
  for (const auto& r : b.positions) b.pressure.push_back(2000.0 - 9810.0 * r.y());
  // The top two rows are the free surface.
  std::vector<int> unknown(b.positions.size(), 0);
  for (std::size_t i = 0; i < b.positions.size(); ++i) {
    if (b.kinds[i] == ParticleKind::fluid && b.positions[i].y() > (rows - 2.5) * l0)
      unknown[i] = -1;
    if (b.kinds[i] == ParticleKind::dummy) unknown[i] = -1;
  }
  GradientInput in = b.input(2, radius_over_l0, l0);
  in.unknown = &unknown;
  std::vector<Eigen::Vector3d> interior, minimum, corrected, wall;
  std::vector<double> work;
  pressure_gradients(Form::corrected_interior, in, interior, wall, work);
  pressure_gradients(Form::minimum, in, minimum, wall, work);
  pressure_gradients(Form::corrected, in, corrected, wall, work);
  int near_surface = 0, full = 0;
  for (std::size_t i = 0; i < b.positions.size(); ++i) {
    if (b.kinds[i] != ParticleKind::fluid) continue;
    bool touches_surface = unknown[i] < 0;
    for (int k = b.list.begin(static_cast<int>(i)); k < b.list.end(static_cast<int>(i)); ++k) {
      const int j = b.list.index[k];
      touches_surface = touches_surface || (b.kinds[j] == ParticleKind::fluid &&
                                            b.list.distance[k] < in.radius && unknown[j] < 0);
    }
    if (touches_surface) {
      EXPECT_EQ(interior[i], minimum[i]) << "particle " << i;
      ++near_surface;
    } else {
      EXPECT_EQ(interior[i], corrected[i]) << "particle " << i;
      EXPECT_GT((corrected[i] - minimum[i]).norm(), 1e-6 * minimum[i].norm()) << "particle " << i;
      ++full;
    }
  }
  EXPECT_GT(near_surface, 0);
  EXPECT_GT(full, 0);
  // Without the unknowns the form cannot tell the surface: refused.
  in.unknown = nullptr;
  EXPECT_THROW(pressure_gradients(Form::corrected_interior, in, interior, wall, work),
               std::invalid_argument);
}

// A fluid particle a quarter of l0 off the wall lattice under uniform pressure: the symmetric
// form's wall share has a tangential part (the lock into the wall's hollows), the normal-wall form
// has none and keeps the normal part.
TEST(MpsPressureGradient, NormalWallPushesAlongTheNormalOnly) {
  const double l0 = 0.01, radius_over_l0 = 4.0;
  Block b = block(2, 20, 10, l0, 0.0, radius_over_l0 * l0, 1);
  const int moved = (3 + 0) * 20 + 10;  // first fluid row, column 10
  ASSERT_EQ(b.kinds[moved], ParticleKind::fluid);
  b.positions[moved].x() += 0.25 * l0;
  NeighbourGrid grid(2, bounding_box(b.positions, 2, radius_over_l0 * l0), radius_over_l0 * l0);
  grid.build(b.positions);
  b.list = grid.neighbours(b.positions, radius_over_l0 * l0);
  b.pressure.assign(b.positions.size(), 800.0);
  std::vector<Eigen::Vector3d> g, wall;
  std::vector<double> minimum;
  pressure_gradients(Form::symmetric, b.input(2, radius_over_l0, l0), g, wall, minimum);
  const Eigen::Vector3d symmetric_wall = wall[moved];
  pressure_gradients(Form::symmetric_normal_wall, b.input(2, radius_over_l0, l0), g, wall, minimum);
  EXPECT_GT(std::abs(symmetric_wall.x()), 1e-3 * std::abs(symmetric_wall.y()));
  EXPECT_LT(std::abs(wall[moved].x()), 1e-12 * std::abs(wall[moved].y()));
  EXPECT_NEAR(wall[moved].y(), symmetric_wall.y(), 1e-12 * std::abs(symmetric_wall.y()));
}

// The step's shifting: A = 2, each shift capped at 0.1 l0.
ShiftingOptions shifting(double dt, double l0, bool taylor, bool tangential_at_walls = false) {
  ShiftingOptions options;
  options.coefficient = 2.0;
  options.dt = dt;
  options.particle_spacing = l0;
  options.max_shift = 0.1 * l0;
  options.taylor = taylor;
  options.tangential_at_walls = tangential_at_walls;
  return options;
}

// Shifting moves a particle pushed towards a neighbour back towards the middle of the gap, and
// not at all at rest or on the free surface.
TEST(MpsPressureGradient, ShiftingMovesAwayFromCrowding) {
  const double l0 = 0.01, radius_over_l0 = 2.1, dt = 1e-3;
  Block b = block(2, 16, 16, l0, 0.0, radius_over_l0 * l0, 1);
  const int moved = (3 + 8) * 16 + 8;
  b.positions[moved].x() += 0.3 * l0;  // towards its right neighbour
  NeighbourGrid grid(2, bounding_box(b.positions, 2, radius_over_l0 * l0), radius_over_l0 * l0);
  grid.build(b.positions);
  b.list = grid.neighbours(b.positions, radius_over_l0 * l0);
  b.pressure.assign(b.positions.size(), 0.0);
  std::vector<int> unknown(b.positions.size(), 0);
  const int top = (3 + 15) * 16 + 8;
  unknown[top] = -1;  // a free-surface particle
  std::vector<Eigen::Vector3d> velocity(b.positions.size(), Eigen::Vector3d(0.5, 0.0, 0.0));
  std::vector<Eigen::Vector3d> out = b.positions;
  const GradientInput in = b.input(2, radius_over_l0, l0);
  const double largest = shift_particles(in, velocity, unknown, shifting(dt, l0, false), out);
  EXPECT_LT(out[moved].x(), b.positions[moved].x());  // back to the left
  EXPECT_GT(largest, 0.0);
  EXPECT_LE(largest, 0.1 * l0 * (1 + 1e-12));
  EXPECT_EQ(out[top], b.positions[top]);
  std::vector<Eigen::Vector3d> rest(b.positions.size(), Eigen::Vector3d::Zero());
  out = b.positions;
  EXPECT_EQ(shift_particles(in, rest, unknown, shifting(dt, l0, false), out), 0.0);
}

// Beside a bed, full shifting lifts the crowded first row off the wall into the faster water of
// a shear flow, and with taylor that lift is momentum no force gave (rigid_canopy's balance,
// docs/validation.md). tangential_at_walls removes the shift across the wall: the first rows
// keep their height and gain nothing, and particles out of the walls' reach shift as before.
TEST(MpsPressureGradient, TangentialShiftingNeverLiftsParticlesOffAWall) {
  const double l0 = 0.01, radius_over_l0 = 2.1, dt = 1e-3;
  const int columns = 16;
  Block b = block(2, columns, 12, l0, 0.0, radius_over_l0 * l0, 1);
  auto row_of = [&](int i) { return static_cast<int>(std::lround(b.positions[i].y() / l0)); };
  for (std::size_t i = 0; i < b.positions.size(); ++i) {
    if (b.kinds[i] == ParticleKind::fluid && row_of(i) == 0) b.positions[i].y() -= 0.3 * l0;
  }
  const int sideways = (3 + 5) * columns + 8;  // row 5, out of the walls' reach
  b.positions[sideways].x() += 0.3 * l0;
  NeighbourGrid grid(2, bounding_box(b.positions, 2, radius_over_l0 * l0), radius_over_l0 * l0);
  grid.build(b.positions);
  b.list = grid.neighbours(b.positions, radius_over_l0 * l0);
  b.pressure.assign(b.positions.size(), 0.0);
  const std::vector<int> unknown(b.positions.size(), 0);
  auto shear = [](const Eigen::Vector3d& x) { return Eigen::Vector3d(0.5 + 20.0 * x.y(), 0, 0); };
  std::vector<Eigen::Vector3d> before(b.positions.size());
  for (std::size_t i = 0; i < before.size(); ++i) before[i] = shear(b.positions[i]);
  const GradientInput in = b.input(2, radius_over_l0, l0);
  std::vector<Eigen::Vector3d> full_u = before, slide_u = before;
  std::vector<Eigen::Vector3d> full = b.positions, slide = b.positions;
  shift_particles(in, full_u, unknown, shifting(dt, l0, true), full);
  shift_particles(in, slide_u, unknown, shifting(dt, l0, true, true), slide);
  Eigen::Vector3d full_gain = Eigen::Vector3d::Zero(), slide_gain = Eigen::Vector3d::Zero();
  int lifted = 0;
  for (std::size_t i = 0; i < b.positions.size(); ++i) {
    if (b.kinds[i] != ParticleKind::fluid) continue;
    const int column = static_cast<int>(i) % columns;
    if (row_of(i) >= 2) {  // no wall within the radius (2.1 l0): the same bits
      EXPECT_EQ(slide[i], full[i]) << i;
      EXPECT_EQ(slide_u[i], full_u[i]) << i;
      continue;
    }
    if (column < 3 || column > columns - 4) continue;  // the block's open sides tilt grad C
    if (full[i].y() - b.positions[i].y() > 1e-3 * l0) ++lifted;
    EXPECT_NEAR(slide[i].y(), b.positions[i].y(), 1e-12 * l0) << i;
    full_gain += full_u[i] - before[i];
    slide_gain += slide_u[i] - before[i];
  }
  EXPECT_GE(lifted, 10) << "the crowded first row is lifted by full shifting";
  EXPECT_GT(full_gain.x(), 1e-3) << "and gains the faster water's momentum";
  EXPECT_LT(slide_gain.norm(), 1e-12) << "tangential: no lift, no gain";
  EXPECT_GT((full[sideways] - b.positions[sideways]).norm(), 1e-3 * l0);
}

// With taylor, a shifted particle takes the flow's velocity at its new place: in a linear
// velocity field (a shear and a stretch) on a disordered block, u_i + J_i dr_i equals the field
// at the shifted position to round-off; without it the velocity stays (and misses it by
// the shift times the gradient, the brink error of free_overfall, docs/validation.md).
TEST(MpsPressureGradient, ShiftedParticlesCarryTheLinearFlowsVelocity) {
  const double l0 = 0.01, radius_over_l0 = 2.1, dt = 1e-3;
  Block b = block(2, 16, 16, l0, 0.2, radius_over_l0 * l0, 9);
  b.pressure.assign(b.positions.size(), 0.0);
  const std::vector<int> unknown(b.positions.size(), 0);
  auto flow = [](const Eigen::Vector3d& x) {
    return Eigen::Vector3d(0.4 + 3.0 * x.y() + 1.5 * x.x(), -1.5 * x.y(), 0.0);
  };
  std::vector<Eigen::Vector3d> kept(b.positions.size());
  for (std::size_t i = 0; i < kept.size(); ++i) kept[i] = flow(b.positions[i]);
  std::vector<Eigen::Vector3d> carried = kept;
  std::vector<Eigen::Vector3d> out_kept = b.positions, out_carried = b.positions;
  const GradientInput in = b.input(2, radius_over_l0, l0);
  shift_particles(in, kept, unknown, shifting(dt, l0, false), out_kept);
  shift_particles(in, carried, unknown, shifting(dt, l0, true), out_carried);
  int shifted = 0;
  double worst = 0.0, stale = 0.0;
  for (std::size_t i = 0; i < b.positions.size(); ++i) {
    if (b.kinds[i] != ParticleKind::fluid) continue;
    EXPECT_EQ(out_kept[i], out_carried[i]) << i;  // the same shifts
    if (out_carried[i] == b.positions[i]) {
      EXPECT_EQ(carried[i], flow(b.positions[i])) << i;
      continue;
    }
    ++shifted;
    EXPECT_EQ(kept[i], flow(b.positions[i])) << i;
    worst = std::max(worst, (carried[i] - flow(out_carried[i])).norm());
    stale = std::max(stale, (kept[i] - flow(out_kept[i])).norm());
  }
  EXPECT_GT(shifted, 100);
  EXPECT_GT(stale, 1e-5);  // the gradient times a shift of up to 1 mm
  EXPECT_LT(worst, 1e-12);
}

// A scene's momentum balance closed (issue 16): in a driven periodic channel with a hump of water
// falling in, the fluid's momentum change equals what gravity, the drive and the walls gave it
// (viscous, collision and pressure impulses booked by the step), to round-off, with the
// symmetric_normal_wall gradient and particle shifting: the fluid-fluid pressure forces cancel
// and shifting moves particles without touching their momentum.
namespace {
// The channel of NormalWallGradientClosesAChannelsMomentumBalance with the shifted particles'
// velocities kept or carried (taylor: its gain is booked as shifting_impulse, nonzero).
void expect_channel_momentum_balance(MpsParameters::ShiftedVelocity carried) {
  const double length = 0.2, depth = 0.06, l0 = 0.01;
  MpsParameters p = cosim::mps::testing::quiet_parameters(l0);
  p.gradient_form = MpsParameters::GradientForm::symmetric_normal_wall;
  p.shifting_coefficient = 2.0;
  p.shifted_velocity = carried;
  p.periodic.driving_pressure_drop = 50.0;
  ParticleSet set = periodic_channel(p, length, depth);
  for (int iy = 0; iy < 4; ++iy)
    for (int ix = 0; ix < 5; ++ix)
      set.add(Eigen::Vector3d(0.1 + (ix + 0.5) * l0, depth + (iy + 0.5) * l0, 0.0),
              ParticleKind::fluid);
  FluidSystem system(p, set);
  const Eigen::Vector3d start = system.total_fluid_momentum();
  Eigen::Vector3d booked = Eigen::Vector3d::Zero(), fluid_fluid = Eigen::Vector3d::Zero(),
                  shifting = Eigen::Vector3d::Zero();
  double magnitude = 0.0;
  for (int k = 0; k < 400; ++k) {
    const double dt = 5e-4;
    const StepReport r = system.step(dt);
    booked += r.body_impulse + r.external_impulse + r.wall_viscous_force * dt +
              r.wall_collision_impulse + r.wall_pressure_impulse + r.shifting_impulse;
    shifting += r.shifting_impulse;
    fluid_fluid += r.pressure_impulse - r.wall_pressure_impulse;
    magnitude += r.pressure_impulse.norm() + r.body_impulse.norm();
  }
  const Eigen::Vector3d change = system.total_fluid_momentum() - start;
  std::cout << "[momentum balance] change (" << change.x() << ", " << change.y() << "), booked ("
            << booked.x() << ", " << booked.y() << "), fluid-fluid pressure (" << fluid_fluid.x()
            << ", " << fluid_fluid.y() << ") N s/m\n";
  EXPECT_LT(fluid_fluid.norm(), 1e-12 * magnitude);
  EXPECT_LT((change - booked).norm(), 1e-12 * magnitude);
  EXPECT_GT(change.x(), 0.0);  // the drive accelerates the water
  if (carried == MpsParameters::ShiftedVelocity::kept) {
    EXPECT_EQ(shifting.norm(), 0.0);
  } else {
    EXPECT_GT(shifting.norm(), 1e-9 * magnitude);  // taylor moves momentum that no force gave
  }
}
}  // namespace

TEST(MpsPressureGradient, NormalWallGradientClosesAChannelsMomentumBalance) {
  for (const auto carried :
       {MpsParameters::ShiftedVelocity::kept, MpsParameters::ShiftedVelocity::taylor}) {
    SCOPED_TRACE(carried == MpsParameters::ShiftedVelocity::kept ? "kept" : "taylor");
    expect_channel_momentum_balance(carried);
  }
}

namespace {

// The blended form's sums at every fluid particle, with the forms it blends.
struct BlendedForms {
  std::vector<Eigen::Vector3d> blended, split, minimum, corrected;
};

BlendedForms blended_forms(const GradientInput& in) {
  BlendedForms f;
  std::vector<Eigen::Vector3d> wall;
  std::vector<double> work;
  pressure_gradients(Form::corrected_blended, in, f.blended, wall, work);
  pressure_gradients(Form::corrected_split, in, f.split, wall, work);
  pressure_gradients(Form::minimum, in, f.minimum, wall, work);
  pressure_gradients(Form::corrected, in, f.corrected, wall, work);
  return f;
}

}  // namespace

// corrected_blended: the weight is 0 on the free surface (the form is the minimum form there,
// bit for bit), 1 in a full neighbourhood (the corrected form), rises with the depth in between,
// where the form is (1 - w) times the minimum form plus w times the corrected one; among solids
// (phi > 0) a thinner neighbourhood counts as full.
TEST(MpsPressureGradient, BlendedWeightGoesFromSurfaceToInterior) {
  const double l0 = 0.01, radius_over_l0 = 4.0;
  const int columns = 24, rows = 14;
  Block b = block(2, columns, rows, l0, 0.0, radius_over_l0 * l0, 1);
  for (const auto& r : b.positions) b.pressure.push_back(1500.0 - 9810.0 * r.y() + 30.0 * r.x());
  GradientInput in = b.input(2, radius_over_l0, l0);
  in.surface_threshold = 0.8;  // so that the second row lies inside the ramp
  auto at_depth = [&](int depth) { return (3 + rows - 1 - depth) * columns + columns / 2; };
  std::vector<double> weights;
  for (int depth = 0; depth < 6; ++depth) weights.push_back(correction_weight(in, at_depth(depth)));
  EXPECT_EQ(weights[0], 0.0);
  EXPECT_GT(weights[1], 0.05);
  EXPECT_LT(weights[1], 0.95);
  for (int depth = 3; depth < 6; ++depth) EXPECT_DOUBLE_EQ(weights[depth], 1.0);
  for (int depth = 1; depth < 6; ++depth) EXPECT_GE(weights[depth], weights[depth - 1]);
  const BlendedForms f = blended_forms(in);
  EXPECT_EQ(f.blended[at_depth(0)], f.minimum[at_depth(0)]);
  EXPECT_EQ(f.split[at_depth(0)], f.minimum[at_depth(0)]);
  EXPECT_LT((f.blended[at_depth(4)] - f.corrected[at_depth(4)]).norm(),
            1e-12 * f.corrected[at_depth(4)].norm());
  const int mid = at_depth(1);
  const Eigen::Vector3d mix = (1.0 - weights[1]) * f.minimum[mid] + weights[1] * f.corrected[mid];
  EXPECT_LT((f.blended[mid] - mix).norm(), 1e-12 * mix.norm());
  EXPECT_GT((f.corrected[mid] - f.minimum[mid]).norm(), 1e-3 * f.minimum[mid].norm());
  // Among solids taking 40 % of the volume, the surface particle's 0.62 n0 is a full
  // neighbourhood of (1 - 0.4) n0.
  std::vector<double> phi(b.positions.size(), 0.4);
  in.solid_fraction = &phi;
  EXPECT_DOUBLE_EQ(correction_weight(in, at_depth(0)), 1.0);
}

// In a full neighbourhood the blended form is exact for a linear pressure, also on a sheared
// lattice (centrally symmetric, so the p^_i part sums to zero, but anisotropic, so the plain
// MPS gradient is not exact there).
TEST(MpsPressureGradient, BlendedGradientOfLinearPressureIsExactInFullNeighbourhood) {
  const double l0 = 0.01, radius_over_l0 = 3.1, shear = 0.3;
  const int columns = 20, rows = 20;
  Block b;
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < columns; ++x) {
      // 3 % closer than l0: a neighbourhood fuller than n0, whatever the shear does to it.
      b.positions.emplace_back(0.97 * (x + shear * y) * l0, 0.97 * y * l0, 0.0);
      b.kinds.push_back(ParticleKind::fluid);
    }
  }
  const double radius = radius_over_l0 * l0;
  NeighbourGrid grid(2, bounding_box(b.positions, 2, radius), radius);
  grid.build(b.positions);
  b.list = grid.neighbours(b.positions, radius);
  const Eigen::Vector3d slope(250.0, -9810.0, 0.0);
  for (const auto& r : b.positions) b.pressure.push_back(4000.0 + slope.dot(r));
  const GradientInput in = b.input(2, radius_over_l0, l0);
  const int centre = (rows / 2) * columns + columns / 2;
  ASSERT_EQ(correction_weight(in, centre), 1.0);
  const BlendedForms f = blended_forms(in);
  const double factor = gradient_factor(2, in.n0);
  EXPECT_LT((factor * f.blended[centre] - slope).norm(), 1e-9 * slope.norm());
  EXPECT_LT((factor * f.split[centre] - slope).norm(), 1e-9 * slope.norm());
  EXPECT_GT((factor * f.minimum[centre] - slope).norm(), 1e-3 * slope.norm());
}

// corrected_split on a disordered block with a hydrostatic pressure: the minimum form plus
// w_i (n0/d C_i - I) sum (p_j - p_i) F_ij, the correction of the Taylor part alone (the
// corrected gradient with p_i as its own reference), p^_i's repulsion left as it is.
TEST(MpsPressureGradient, SplitCorrectsTheTaylorPartOnly) {
  const double l0 = 0.01, radius_over_l0 = 3.1;
  const int columns = 16, rows = 12;
  Block b = block(2, columns, rows, l0, 0.2, radius_over_l0 * l0, 9);
  for (const auto& r : b.positions) b.pressure.push_back(1200.0 - 9810.0 * r.y());
  const GradientInput in = b.input(2, radius_over_l0, l0);
  const BlendedForms f = blended_forms(in);
  const std::vector<Eigen::Vector3d> taylor = corrected_gradient(in, b.pressure, b.pressure);
  const double factor = gradient_factor(2, in.n0);
  // The uncorrected Taylor part d/n0 sum (p_j - p_i) F_ij over the pressure-carrying partners.
  auto plain = [&](int i) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int k = b.list.begin(i); k < b.list.end(i); ++k) {
      const int j = b.list.index[k];
      if (b.kinds[j] == ParticleKind::dummy || b.list.distance[k] >= in.radius) continue;
      sum += gradient_pair_term(b.pressure[j] - b.pressure[i], b.list.distance[k], in.radius,
                                b.positions[j] - b.positions[i]);
    }
    return Eigen::Vector3d(factor * sum);
  };
  int partial = 0, corrected = 0;
  for (std::size_t i = 0; i < b.kinds.size(); ++i) {
    if (b.kinds[i] != ParticleKind::fluid) continue;
    const double w = correction_weight(in, static_cast<int>(i));
    // corrected_gradient is C_i sum, gradient() is d/n0 sum: both in Pa/m.
    const Eigen::Vector3d expected =
        f.minimum[i] + w * (taylor[i] - plain(static_cast<int>(i))) / factor;
    EXPECT_LT((f.split[i] - expected).norm(), 1e-9 * f.minimum[i].norm()) << "particle " << i;
    partial += w > 0.0 && w < 1.0;
    corrected += w == 1.0;
  }
  EXPECT_GT(partial, 0);
  EXPECT_GT(corrected, 0);
}

// The hydrostatic background (hydrostatic_background.hpp): on a disordered column of water at
// rest with its hydrostatic pressure, the minimum form's fluid-fluid forces do not cancel
// sideways (the non-conservation the rigid_canopy balance missed); carrying only q = p - p_b,
// with grad p_b added exactly, leaves a fraction of that sideways sum.
TEST(MpsPressureGradient, HydrostaticBackgroundCutsTheSidewaysNonConservation) {
  const double l0 = 0.01, radius_over_l0 = 4.0, rho = 1000.0, g = 9.81;
  Block b = block(2, 40, 24, l0, 0.15, radius_over_l0 * l0, 7);
  double top = -1.0;
  for (std::size_t i = 0; i < b.kinds.size(); ++i) {
    if (b.kinds[i] == ParticleKind::fluid) top = std::max(top, b.positions[i].y());
  }
  b.pressure.assign(b.kinds.size(), 0.0);
  for (std::size_t i = 0; i < b.kinds.size(); ++i) {
    if (b.kinds[i] != ParticleKind::dummy)
      b.pressure[i] = rho * g * (top + 0.5 * l0 - b.positions[i].y());
  }
  const GradientInput in = b.input(2, radius_over_l0, l0);
  const double scale = 2.0 / in.n0;  // d / n0: the sums are in units of it
  const double plain = scale * fluid_fluid_sum(Form::minimum, b, 2, radius_over_l0, l0).first.x();

  BackgroundInput background;
  background.dimension = 2;
  background.gravity = Eigen::Vector3d(0.0, -g, 0.0);
  background.density = rho;
  background.particle_spacing = l0;
  background.taper_depth = radius_over_l0 * l0;
  background.positions = &b.positions;
  background.kinds = &b.kinds;
  background.periodic = &b.periodic;
  BackgroundField field;
  hydrostatic_background(background, field);
  // The step's correction: S (<grad q> + grad p_b) + (1 - S) <grad p>, q = p - p_b.
  std::vector<Eigen::Vector3d> whole, whole_wall, dynamic, dynamic_wall;
  std::vector<double> minimum;
  pressure_gradients(Form::minimum, in, whole, whole_wall, minimum);
  for (std::size_t i = 0; i < b.kinds.size(); ++i) b.pressure[i] -= field.pressure[i];
  pressure_gradients(Form::minimum, in, dynamic, dynamic_wall, minimum);
  double exact = 0.0, split = 0.0, trusted = 0.0, fluid = 0.0;
  for (std::size_t i = 0; i < b.kinds.size(); ++i) {
    if (b.kinds[i] != ParticleKind::fluid) continue;
    const double s = field.trust[i];
    exact += s * field.gradient[i].x();
    split += scale *
             (s * (dynamic[i] - dynamic_wall[i]).x() + (1.0 - s) * (whole[i] - whole_wall[i]).x());
    trusted += s;
    fluid += 1.0;
  }
  split += exact;
  EXPECT_GT(trusted, 0.5 * fluid);  // the column is mostly trusted: the split does the work
  std::cout << "[hydrostatic column] sideways fluid-fluid pressure force sum, p " << plain
            << " Pa/m, q + grad p_b " << split << " Pa/m (of which exact " << exact
            << "); one particle's weight " << rho * g << " Pa/m\n";
  EXPECT_GT(std::abs(plain), 0.1 * rho * g);
  EXPECT_LT(std::abs(split), std::abs(plain) / 3.0);
}

TEST(MpsPressureGradient, UntrustedBackgroundStepsAsTheOperatorAlone) {
  // A block of water in free fall: no wall holds it up, so the background's trust S is 0 in
  // every column, and the correction, S (<grad q> + grad p_b) + (1 - S) <grad p>, is the
  // operator's on the whole pressure, bit for bit.
  MpsParameters plain;
  plain.particle_spacing = 0.01;
  ParticleSet block;
  for (int i = 0; i < 12; ++i) {
    for (int j = 0; j < 12; ++j) {
      // Squeezed towards its centre, so that it has a pressure to take the gradient of.
      const Eigen::Vector3d x((i + 0.5) * 0.01, 0.5 + (j + 0.5) * 0.01, 0.0);
      block.add(x, ParticleKind::fluid, -5.0 * (x - Eigen::Vector3d(0.06, 0.56, 0.0)));
    }
  }
  MpsParameters with = plain;
  with.pressure_background = MpsParameters::PressureBackground::hydrostatic;
  FluidSystem alone(plain, block), background(with, block);
  for (int step = 0; step < 5; ++step) {
    alone.step(1e-3);
    background.step(1e-3);
  }
  double largest_pressure = 0.0;
  for (std::size_t i = 0; i < block.size(); ++i) {
    EXPECT_EQ(alone.positions()[i], background.positions()[i]) << i;
    largest_pressure = std::max(largest_pressure, alone.pressures()[i]);
  }
  EXPECT_GT(largest_pressure, 0.0);
}

TEST(MpsPressureGradient, EvaluatingSomeParticlesGivesTheirSumsBitForBit) {
  // The step asks for each of its two estimates only where its weight is not zero: the particles
  // asked for get the bits of a full evaluation, the others zero sums.
  const double l0 = 0.01, radius_over_l0 = 3.1;
  Block b = block(2, 16, 10, l0, 0.2, radius_over_l0 * l0, 5);
  std::mt19937 random(3);
  std::uniform_real_distribution<double> pressure(0.0, 1000.0);
  for (std::size_t i = 0; i < b.kinds.size(); ++i) b.pressure.push_back(pressure(random));
  const GradientInput in = b.input(2, radius_over_l0, l0);
  std::vector<char> evaluate(b.kinds.size());
  for (std::size_t i = 0; i < evaluate.size(); ++i) evaluate[i] = i % 3 == 0;
  for (const Form form : {Form::minimum, Form::corrected_blended, Form::symmetric}) {
    std::vector<Eigen::Vector3d> all, all_wall, some, some_wall;
    std::vector<double> minimum;
    pressure_gradients(form, in, all, all_wall, minimum);
    pressure_gradients(form, in, some, some_wall, minimum, &evaluate);
    int asked = 0;
    for (std::size_t i = 0; i < b.kinds.size(); ++i) {
      if (b.kinds[i] != ParticleKind::fluid) continue;
      if (evaluate[i]) {
        EXPECT_EQ(some[i], all[i]) << i;
        EXPECT_EQ(some_wall[i], all_wall[i]) << i;
        asked += all[i].norm() > 0.0;
      } else {
        EXPECT_EQ(some[i].norm(), 0.0) << i;
        EXPECT_EQ(some_wall[i].norm(), 0.0) << i;
      }
    }
    EXPECT_GT(asked, 20);
  }
}

// A regular 2D column of water at rest (21 x 24 particles, l0 = 1 cm, radius 3.1 l0) with the
// particle of column 10, row 8 moved by `shift`, its pair list, and its hydrostatic background
// (the blend's linear one with `blend`).
constexpr double kColumnSpacing = 0.01, kColumnRadiusOverL0 = 3.1;
constexpr int kColumnColumns = 21, kColumnRows = 24;
struct MovedColumn {
  Block block;
  int moved = -1;
  BackgroundField field;
};
MovedColumn moved_column(const Eigen::Vector3d& shift, bool blend) {
  const double l0 = kColumnSpacing, radius = kColumnRadiusOverL0 * kColumnSpacing;
  MovedColumn c;
  Block& b = c.block;
  b = block(2, kColumnColumns, kColumnRows, l0, 0.0, radius, 1);
  for (std::size_t i = 0; i < b.kinds.size(); ++i) {
    const Eigen::Vector3d& r = b.positions[i];
    if (b.kinds[i] == ParticleKind::fluid && std::abs(r.x() - 10 * l0) < 1e-9 &&
        std::abs(r.y() - 8 * l0) < 1e-9)
      c.moved = static_cast<int>(i);
  }
  if (c.moved < 0) return c;
  b.positions[c.moved] += shift;
  NeighbourGrid grid(2, bounding_box(b.positions, 2, radius), radius);
  grid.build(b.positions);
  b.list = grid.neighbours(b.positions, radius);
  BackgroundInput background;
  background.dimension = 2;
  background.gravity = Eigen::Vector3d(0.0, -9.81, 0.0);
  background.density = 1000.0;
  background.particle_spacing = l0;
  background.taper_depth = radius;
  background.blend_fade = blend;
  background.positions = &b.positions;
  background.kinds = &b.kinds;
  background.periodic = &b.periodic;
  hydrostatic_background(background, c.field);
  return c;
}

// background_repulsion: full (add_full_pressure_repulsion). On a regular column of water at rest
// with its hydrostatic pressure, one deep particle moved 0.2 l0 sideways: the form on q alone
// barely pushes it (q is the same constant all around it, so neither its Taylor part nor its
// repulsion has anything to act on), the full pressure's repulsion pushes it back towards its
// place. And everywhere the sums are the Taylor part on q plus the whole pressure's repulsion
// (faded in with the background): the whole pressure's minimum form less the form's own Taylor
// part on p_b, below the fade-in layer.
TEST(MpsPressureGradient, FullRepulsionPushesAMovedParticleBack) {
  const double l0 = kColumnSpacing, rho = 1000.0, g = 9.81, radius_over_l0 = kColumnRadiusOverL0;
  const int rows = kColumnRows, columns = kColumnColumns;
  const double shift = 0.2 * l0;
  MovedColumn column = moved_column(Eigen::Vector3d(shift, 0.0, 0.0), false);
  Block& b = column.block;
  const int moved = column.moved;
  ASSERT_GE(moved, 0);
  const BackgroundField& field = column.field;
  const double surface = (rows - 0.5) * l0;
  b.pressure.assign(b.kinds.size(), 0.0);
  for (std::size_t i = 0; i < b.kinds.size(); ++i) {
    if (b.kinds[i] != ParticleKind::dummy) b.pressure[i] = rho * g * (surface - b.positions[i].y());
  }
  const std::vector<double> whole_pressure = b.pressure;
  GradientInput in = b.input(2, radius_over_l0, l0);
  std::vector<Eigen::Vector3d> whole, whole_wall;
  std::vector<double> minimum;
  pressure_gradients(Form::minimum, in, whole, whole_wall, minimum);
  std::vector<double> q(b.kinds.size());
  for (std::size_t i = 0; i < q.size(); ++i) q[i] = whole_pressure[i] - field.pressure[i];
  in.pressure = &q;
  std::vector<Eigen::Vector3d> dynamic, dynamic_wall;
  pressure_gradients(Form::minimum, in, dynamic, dynamic_wall, minimum);
  std::vector<Eigen::Vector3d> full = dynamic, full_wall = dynamic_wall;
  std::vector<double> full_minimum;
  add_full_pressure_repulsion(Form::minimum, in, minimum, whole_pressure, field.fade, nullptr, full,
                              full_wall, full_minimum);
  // The force is -V d/n0 times the sum: a positive x sum pushes back towards -x.
  const double factor = gradient_factor(2, in.n0);
  const double back = factor * full[moved].x(), alone = factor * dynamic[moved].x();
  std::cout << "[moved particle] sideways gradient, q's form " << alone
            << " Pa/m, with the full repulsion " << back << " Pa/m (rho g = " << rho * g << ")\n";
  EXPECT_GT(back, 0.05 * rho * g);
  EXPECT_LT(std::abs(alone), 0.01 * back);
  // The split, particle by particle: below the fade-in layer (f' = 1) full = whole - sum
  // (p_b,j - p_b,i) F_ij; within it the added repulsion is f' times that one.
  int checked = 0, faded = 0;
  for (std::size_t i = 0; i < b.kinds.size(); ++i) {
    if (b.kinds[i] != ParticleKind::fluid) continue;
    Eigen::Vector3d background_taylor = Eigen::Vector3d::Zero(),
                    background_wall = Eigen::Vector3d::Zero();
    for (int k = b.list.begin(static_cast<int>(i)); k < b.list.end(static_cast<int>(i)); ++k) {
      const int j = b.list.index[k];
      if (b.kinds[j] == ParticleKind::dummy || b.list.distance[k] >= in.radius) continue;
      const Eigen::Vector3d term =
          gradient_pair_term(field.pressure[j] - field.pressure[i], b.list.distance[k], in.radius,
                             b.positions[j] - b.positions[i]);
      background_taylor += term;
      if (b.kinds[j] != ParticleKind::fluid) background_wall += term;
    }
    const double scale = whole[i].norm() + background_taylor.norm();
    const double f = field.fade[i];
    const Eigen::Vector3d expected = dynamic[i] + f * (whole[i] - background_taylor - dynamic[i]);
    const Eigen::Vector3d expected_wall =
        dynamic_wall[i] + f * (whole_wall[i] - background_wall - dynamic_wall[i]);
    EXPECT_LT((full[i] - expected).norm(), 1e-12 * scale) << i;
    EXPECT_LT((full_wall[i] - expected_wall).norm(), 1e-12 * scale) << i;
    ++checked;
    faded += f < 1.0;
  }
  EXPECT_EQ(checked, columns * rows);
  EXPECT_GT(faded, columns);  // the top layers are within the fade-in
}

// background_replaces: layer_mean (keep_layer_deviation). The same column with one particle moved
// 0.2 l0 down, the linear background of the blend fade-in (q = 0 everywhere): each particle
// gets its Taylor part on p_b less the mean of its layer. The moved particle's sum departs from
// its layer's (the dependence on the arrangement that the background alone takes away), the
// added forces of every layer sum to zero (no net momentum), and particles with the same
// neighbourhood get the same addition.
TEST(MpsPressureGradient, LayerDeviationKeepsTheStiffnessAndNoNetForce) {
  const double l0 = kColumnSpacing, rho = 1000.0, g = 9.81, radius_over_l0 = kColumnRadiusOverL0;
  // Down into its own row's layer (l0 / 2 thick).
  MovedColumn column = moved_column(Eigen::Vector3d(0.0, -0.2 * l0, 0.0), true);
  Block& b = column.block;
  const int moved = column.moved;
  ASSERT_GE(moved, 0);
  const BackgroundField& field = column.field;
  b.pressure = field.pressure;
  GradientInput in = b.input(2, radius_over_l0, l0);
  const int n = static_cast<int>(b.kinds.size());
  std::vector<char> everywhere(n, 1);
  std::vector<int> order(n);
  for (int i = 0; i < n; ++i) order[i] = n - 1 - i;
  std::vector<Eigen::Vector3d> added(n, Eigen::Vector3d::Zero()), taylor;
  const double layer = rho * g * 0.5 * l0;
  keep_layer_deviation(Form::minimum, in, field.pressure, layer, everywhere, order, taylor, added);
  const double factor = gradient_factor(2, in.n0);
  std::cout << "[layer deviation] moved particle: vertical " << factor * added[moved].y()
            << " Pa/m (rho g = " << rho * g << ")\n";
  // Its neighbours are no longer symmetric about it: the sum's vertical moment is larger than its
  // row's, and the added (negative) gradient pushes it back up (-655 Pa/m).
  EXPECT_LT(factor * added[moved].y(), -0.01 * rho * g);
  std::map<long, Eigen::Vector3d> sums;
  std::map<long, double> scales;
  for (int i = 0; i < n; ++i) {
    if (b.kinds[i] != ParticleKind::fluid) continue;
    const long k = static_cast<long>(std::max(field.pressure[i], 0.0) / layer);
    sums.try_emplace(k, Eigen::Vector3d::Zero()).first->second += added[i];
    scales[k] += taylor[i].norm();
  }
  for (const auto& [k, sum] : sums) EXPECT_LT(sum.norm(), 1e-12 * scales[k]) << "layer " << k;
  // Two particles of a deep row with the same neighbourhood (away from the moved particle and the
  // side walls, whose neighbours pull the layer's mean off theirs) get the same addition.
  int pairs = 0;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d& r = b.positions[i];
    if (b.kinds[i] != ParticleKind::fluid || std::abs(r.y() - 16 * l0) > 1e-9) continue;
    if (std::abs(r.x() - 7 * l0) > 1e-9) continue;
    for (int j = 0; j < n; ++j) {
      const Eigen::Vector3d& s = b.positions[j];
      if (b.kinds[j] == ParticleKind::fluid && std::abs(s.y() - r.y()) < 1e-9 &&
          std::abs(s.x() - 13 * l0) < 1e-9) {
        EXPECT_LT((added[i] - added[j]).norm(), 1e-9 * taylor[i].norm());
        ++pairs;
      }
    }
  }
  EXPECT_EQ(pairs, 1);
}
