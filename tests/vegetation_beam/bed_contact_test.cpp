// Bed contact of the plants (bed_contact.cpp): no node passes below the bed plane, and the part
// of a cantilever lying on the bed carries its load straight into the bed as beam theory says.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "beam_test_helpers.hpp"

namespace cosim::vegetation {
namespace {

// Neutrally buoyant (the weight and the buoyancy cancel) so that the only load is the external
// one; gravity still sets the bed normal (+z).
BeamParameters neutral_parameters(bool bed) {
  BeamParameters p = testing::vacuum_parameters();
  p.gravity = Eigen::Vector3d(0, 0, -9.81);
  p.fluid_density = 1000;
  p.added_mass_coefficient = 0;
  p.bed_contact = bed;
  return p;
}

// A uniform load q (N/m) along -z, lumped to the nodes by their length shares.
std::vector<Eigen::Vector3d> uniform_load(const PlantField& field, double q) {
  const PlantSpec& spec = field.specs()[0];
  const double l0 = spec.length / spec.links;
  std::vector<Eigen::Vector3d> forces(field.node_count(), Eigen::Vector3d(0, 0, -q * l0));
  forces.back() *= 0.5;
  return forces;
}

// A cantilever clamped horizontally at the height d + t/2 above a rigid bed, under a uniform
// load q strong enough to bring it down to the bed. Euler-Bernoulli theory (w measured down from
// the clamp): on the free span 0 <= x <= a, EI w'''' = q with w(0) = w'(0) = 0 and, at the
// touchdown, w(a) = d, w'(a) = 0, M(a) = EI w''(a) = 0 (the lying part is straight and carries no
// moment). The solution is w(x) = q (x^4 / 24 - a x^3 / 9 + a^2 x^2 / 12) / EI with
// a = (72 EI d / q)^(1/4); the bed takes q per length beyond a plus a point reaction q a / 3 at
// the touchdown (the shear there), the clamp the other 2 q a / 3.
TEST(BedContact, CantileverPressedOntoTheBedFollowsBeamTheory) {
  PlantSpec spec = testing::textbook_strip(100);
  spec.direction = Eigen::Vector3d::UnitX();
  spec.thickness = 1e-3;  // EI = 1e9 * 0.01 * 1e-9 / 12 = 8.33e-4 N m^2
  const double d = 0.01, t = spec.thickness, length = spec.length;
  const double ei = spec.youngs_modulus * spec.width * std::pow(t, 3) / 12;
  const double a = 0.3 * length;
  const double q = 72 * ei * d / std::pow(a, 4);  // 0.074 N/m
  BeamParameters p = neutral_parameters(true);
  p.bed_below_base = d + 0.5 * t;  // the lying blade's mid-plane is then d below the clamp
  PlantField field({spec}, p);
  field.set_external_forces(uniform_load(field, q));
  field.solve_static(1e-12, 200);

  const double bed_mid_plane = -d;  // node height of a blade lying on the bed
  const double tolerance = 1e-6;    // m: the penalty's penetration is q l0 / k = 7e-11 m
  const double l0 = length / spec.links;
  double lowest = 0, reaction = 0;
  const double k = spec.youngs_modulus * spec.width * t / l0;  // the default bed stiffness EA/l0
  for (int i = 1; i <= spec.links; ++i) {
    const Eigen::Vector3d& x = field.positions()[i];
    lowest = std::min(lowest, x.z() - bed_mid_plane);
    reaction += k * std::max(0.0, bed_mid_plane - x.z());
    const double s = i * l0;
    if (s <= a - 2 * l0) {  // the free span: the beam-theory shape, to 1 % of the gap
      const double w = q * (std::pow(s, 4) / 24 - a * std::pow(s, 3) / 9 + a * a * s * s / 12) / ei;
      EXPECT_NEAR(-x.z(), w, 0.01 * d) << "node " << i;
    } else if (s >= a + 2 * l0) {  // the lying part: flat on the bed
      EXPECT_NEAR(x.z(), bed_mid_plane, tolerance) << "node " << i;
    }
  }
  EXPECT_GT(lowest, -tolerance);
  // The bed carries q (L - a) plus the touchdown's q a / 3: 2 % (the lumped chain, l0 = L / 100).
  EXPECT_NEAR(reaction, q * (length - 2 * a / 3), 0.02 * q * length);
  // Without the bed the same load bends the blade far through it (tip q L^4 / 8 EI = 11 m in
  // linear theory; the chain's links keep it within a length of the clamp).
  PlantField free({spec}, neutral_parameters(false));
  free.set_external_forces(uniform_load(free, q));
  free.solve_static(1e-12, 200);
  EXPECT_LT(free.positions().back().z(), -0.5 * length);
}

// A blade standing on the bed is pressed flat by a strong uniform load down and downstream,
// integrated in time at safety_factor 10 (sub-steps 10 times the axial spring-mass period, as in
// the resolved scenes): no node goes below the bed by more than the penalty's static
// penetration, and the blade ends lying on it, at rest.
TEST(BedContact, StandingBladePressedFlatStaysAboveTheBed) {
  PlantSpec spec = testing::textbook_strip(20);
  spec.direction = Eigen::Vector3d::UnitZ();
  spec.length = 0.06;
  spec.width = 0.02;
  spec.thickness = 5e-4;
  spec.youngs_modulus = 2e8;  // EI = 4.2e-5 N m^2, EA = 2000 N
  BeamParameters p = neutral_parameters(true);
  p.bending_damping_ratio = 0.5;
  p.axial_damping_ratio = 0.5;
  p.safety_factor = 10;
  PlantField field({spec}, p);
  const double l0 = spec.length / spec.links;
  // 20 N/m each way: a linear-theory tip deflection q L^4 / 8 EI of 13 lengths.
  const double q = 20;
  std::vector<Eigen::Vector3d> forces(field.node_count(), Eigen::Vector3d(q * l0, 0, -q * l0));
  field.set_external_forces(forces);
  const std::vector<Eigen::Vector3d> still = testing::uniform(field, Eigen::Vector3d::Zero());
  const double bed_mid_plane = 0.5 * spec.thickness;
  // The default bed spring at safety_factor 10: EA / l0 / 10^2 = 6.7e3 N/m; a node carrying
  // q l0 sits q l0 / k = 9 um deep.
  const double k = spec.youngs_modulus * spec.width * spec.thickness / l0 / 100;
  const double penetration = q * l0 / k;
  double lowest = 1;
  for (int window = 0; window < 400; ++window) {
    field.advance(1e-3, still, still);
    for (int i = 1; i < field.node_count(); ++i)
      lowest = std::min(lowest, field.positions()[i].z() - bed_mid_plane);
  }
  // A node arriving at speed v dips about v sqrt(m / k) deeper (67 um at 1 m/s): the run stays
  // within a fifth of the thickness.
  EXPECT_GT(lowest, -0.2 * spec.thickness);
  for (int i = 16; i < field.node_count(); ++i) {  // the lying part, l0 = 3 mm
    EXPECT_NEAR(field.positions()[i].z(), bed_mid_plane - penetration, 0.2 * penetration)
        << "node " << i;
    EXPECT_LT(field.velocities()[i].norm(), 1e-6) << "node " << i;
  }
  EXPECT_GT(field.positions().back().x(), 0.9 * spec.length);
  // The default spring does not shorten the sub-step; a stiffer given one does.
  EXPECT_NEAR(field.stable_substep(), 10 * std::sqrt(1000 * 0.02 * 5e-4 * l0 / (100 * k)), 1e-12);
  BeamParameters stiff = p;
  stiff.bed_stiffness = 100 * k;
  EXPECT_NEAR(PlantField({spec}, stiff).stable_substep(), field.stable_substep() / 10, 1e-12);
}

// Without bed_contact nothing changes: the same load drives the blade through the bed.
TEST(BedContact, OffByDefault) {
  EXPECT_FALSE(BeamParameters{}.bed_contact);
  PlantSpec spec = testing::textbook_strip(10);
  spec.direction = Eigen::Vector3d::UnitZ();
  spec.thickness = 1e-3;
  PlantField field({spec}, neutral_parameters(false));
  field.set_external_forces(std::vector<Eigen::Vector3d>(field.node_count(), {0.1, 0, -0.1}));
  field.solve_static(1e-12, 200);
  EXPECT_LT(field.positions().back().z(), -0.1);
}

}  // namespace
}  // namespace cosim::vegetation
