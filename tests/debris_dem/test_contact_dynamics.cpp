// Contact dynamics against the closed forms of references/dem_contact.md.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "cosim/debris_dem/dem_world.hpp"
#include "cosim/debris_dem/scenes.hpp"

namespace cosim::dem {
namespace {

DemParameters no_gravity(double dt) {
  DemParameters p;
  p.gravity.setZero();
  p.user_dt = dt;
  return p;
}

struct HeadOn {
  double restitution;
  double contact_time;
};

// Two equal spheres approach head-on at +-v; returns e = separation / approach speed and the
// time the pair was touching.
HeadOn head_on(const Material& m, bool clip) {
  const double r = 0.01;
  const double mass = m.density * 4.0 / 3.0 * std::numbers::pi * r * r * r;
  // About 1100 steps per contact: the integrator's share of the error in e stays below 0.2 %.
  const double dt = 0.002 * std::sqrt(mass / m.normal_stiffness);
  DemParameters p = no_gravity(dt);
  p.clip_normal_force = clip;
  DemWorld world(p);
  const int a = world.add_sphere({-r - 1e-4, 0, 0}, r, m);
  const int b = world.add_sphere({r + 1e-4, 0, 0}, r, m);
  world.set_velocity(a, {0.5, 0, 0});
  world.set_velocity(b, {-0.5, 0, 0});
  double touching_time = 0.0;
  for (int k = 0; k < 200000; ++k) {
    world.step(dt);
    if (world.contact_count() > 0) touching_time += dt;
    if (touching_time > 0.0 && world.contact_count() == 0) break;
  }
  return {(world.velocity(b).x() - world.velocity(a).x()) / 1.0, touching_time};
}

TEST(ContactDynamics, HeadOnRestitutionIsTheAskedOneUnderBothNormalLaws) {
  for (const bool clip : {false, true}) {
    // e = 0.1 needs an overdamped dashpot (zeta > 1) under the clipped law.
    for (const double e : {0.1, 0.3, 0.5, 0.527, 0.9}) {
      Material m;
      m.restitution = e;
      m.normal_stiffness = 1e5;
      const HeadOn impact = head_on(m, clip);
      std::printf("%s law, asked e %.3f: measured %.4f (%+.2f %%), t_c %.4e s\n",
                  clip ? "clipped" : "unclipped", e, impact.restitution,
                  100.0 * (impact.restitution / e - 1.0), impact.contact_time);
      EXPECT_NEAR(impact.restitution, e, 0.01 * e) << (clip ? "clipped" : "unclipped");
    }
  }
}

TEST(ContactDynamics, ClippedRestitutionFormulaAndItsInverse) {
  // Continuous across critical damping, where the underdamped and overdamped forms meet at
  // exp(-2) (Schwager & Poeschel 2007).
  EXPECT_NEAR(clipped_restitution(1.0 - 1e-5), std::exp(-2.0), 1e-4);
  EXPECT_NEAR(clipped_restitution(1.0 + 1e-5), std::exp(-2.0), 1e-4);
  EXPECT_DOUBLE_EQ(clipped_restitution(0.0), 1.0);
  double previous = 1.0;
  for (double zeta = 0.05; zeta < 20.0; zeta *= 1.2) {
    const double e = clipped_restitution(zeta);
    EXPECT_LT(e, previous) << zeta;  // monotonic, so the inverse is unique
    previous = e;
  }
  for (const double e : {0.01, 0.1, std::exp(-2.0), 0.3, 0.5, 0.9, 0.999}) {
    const double zeta = damping_ratio_for_restitution(e, true);
    EXPECT_NEAR(clipped_restitution(zeta), e, 1e-12 * e) << e;
    // The clipped law ends the contact early, so it needs more damping for the same e.
    EXPECT_GT(zeta, damping_ratio_for_restitution(e, false)) << e;
  }
}

TEST(ContactDynamics, UnclippedContactTimeMatchesTheDampedOscillator) {
  // t_c = pi / omega_d, omega_d = sqrt(k / m_eff) sqrt(1 - zeta^2) (references/dem_contact.md).
  for (const double e : {0.3, 0.527, 0.9}) {
    Material m;
    m.restitution = e;
    m.normal_stiffness = 1e5;
    const double zeta =
        -std::log(e) / std::sqrt(std::numbers::pi * std::numbers::pi + std::log(e) * std::log(e));
    const double mass = m.density * 4.0 / 3.0 * std::numbers::pi * 1e-6;
    const double omega_d =
        std::sqrt(m.normal_stiffness / (0.5 * mass)) * std::sqrt(1 - zeta * zeta);
    const HeadOn impact = head_on(m, false);
    EXPECT_NEAR(impact.contact_time, std::numbers::pi / omega_d, 0.02 * std::numbers::pi / omega_d);
  }
  // Damping ratio 0.2 of seed 004 table 3 is e = 0.527 (dem_contact.md) with the dashpot free to
  // pull, and 0.572 under the no-tension law (Schwager & Poeschel 2007).
  Material seed;
  seed.damping_ratio = 0.2;
  EXPECT_NEAR(head_on(seed, false).restitution, 0.527, 0.004);
  EXPECT_NEAR(head_on(seed, true).restitution, 0.572, 0.004);
}

struct Oblique {
  double normal_restitution;
  double tangential_restitution;
  double spin;  // about the axis normal to the plane of incidence (+y), rad/s
};

// A sphere hits a flat triangle at speed 3.9 m/s, theta from the normal (Chung & Ooi 2011
// test 4 sizes: R = 2.5 mm, alumina 4000 kg/m^3, mu = 0.092).
Oblique oblique_impact(double theta_degrees, double restitution, bool clip) {
  Material m;
  m.density = 4000;
  m.normal_stiffness = 1e6;
  m.tangential_stiffness = 0.8e6;
  m.restitution = restitution;
  m.friction = 0.092;
  const double r = 0.0025;
  DemParameters p = no_gravity(1e-7);
  p.clip_normal_force = clip;
  DemWorld world(p);
  world.add_triangle({-1, -1, 0}, {1, -1, 0}, {0, 1, 0}, m);
  const int s = world.add_sphere({0, 0, r + 1e-6}, r, m);
  const double theta = theta_degrees * std::numbers::pi / 180;
  const double vt = 3.9 * std::sin(theta);
  const double vn = 3.9 * std::cos(theta);
  world.set_velocity(s, {vt, 0, -vn});
  bool touched = false;
  for (int k = 0; k < 100000; ++k) {
    world.step(p.user_dt);
    touched = touched || world.contact_count() > 0;
    if (touched && world.contact_count() == 0) break;
  }
  return {world.velocity(s).z() / vn, world.velocity(s).x() / vt, world.angular_velocity(s).y()};
}

// Oblique impact of Chung & Ooi (2011) test 4 on a flat triangle: e = 0.98, sliding throughout
// for tan(theta) >= 3.5 mu (1+e).
TEST(ContactDynamics, ObliqueImpactSlidingMatchesChungOoi) {
  const double mu = 0.092;
  const double r = 0.0025;
  for (const double theta_degrees : {40.0, 60.0, 80.0}) {
    const Oblique out = oblique_impact(theta_degrees, 0.98, true);
    const double theta = theta_degrees * std::numbers::pi / 180;
    const double e = out.normal_restitution;
    ASSERT_GT(std::tan(theta), 3.5 * mu * (1 + e));
    const double expected_et = 1 - mu * (1 + e) / std::tan(theta);
    EXPECT_NEAR(out.tangential_restitution, expected_et, 0.01) << theta_degrees;
    const double expected_spin = 5 * mu * (1 + e) * 3.9 * std::cos(theta) / (2 * r);
    std::printf("theta %.0f: e_n %.4f, e_t %.4f (analytic %.4f), spin %.1f (analytic %.1f) rad/s\n",
                theta_degrees, e, out.tangential_restitution, expected_et, out.spin, expected_spin);
    EXPECT_NEAR(out.spin, expected_spin, 0.02 * expected_spin) << theta_degrees;
  }
}

// A strongly damped sliding impact (asked e = 0.5) against the closed forms of
// references/dem_contact.md written with the asked e: the friction impulse must be mu times the
// normal impulse under either normal law.
TEST(ContactDynamics, DampedSlidingImpactMatchesClosedFormsUnderBothNormalLaws) {
  const double mu = 0.092;
  const double e = 0.5;
  const double r = 0.0025;
  for (const bool clip : {false, true}) {
    for (const double theta_degrees : {30.0, 50.0, 70.0}) {
      const double theta = theta_degrees * std::numbers::pi / 180;
      ASSERT_GT(std::tan(theta), 3.5 * mu * (1 + e));
      const Oblique out = oblique_impact(theta_degrees, e, clip);
      const double vn = 3.9 * std::cos(theta);
      const double vt = 3.9 * std::sin(theta);
      const double expected_et = 1 - mu * (1 + e) / std::tan(theta);
      const double expected_spin = 5 * mu * (1 + e) * vn / (2 * r);
      // Friction impulse over mu times the normal impulse, both measured (1 when sliding).
      const double impulse_ratio =
          (1 - out.tangential_restitution) * vt / (mu * (1 + out.normal_restitution) * vn);
      std::printf(
          "%s law, theta %.0f: e_n %.4f (asked %.2f), e_t %.5f (closed form %.5f, %+.2f %%), "
          "friction/normal impulse %.4f / mu, spin %.1f (closed form %.1f, %+.2f %%)\n",
          clip ? "clipped" : "unclipped", theta_degrees, out.normal_restitution, e,
          out.tangential_restitution, expected_et,
          100 * (out.tangential_restitution / expected_et - 1), impulse_ratio, out.spin,
          expected_spin, 100 * (out.spin / expected_spin - 1));
      EXPECT_NEAR(out.normal_restitution, e, 0.01 * e);
      // Clipped, the cap is the transmitted force itself: exact. Unclipped, the cap k delta
      // misses the dashpot impulse of the first and last step, c (v_in + v_out) dt, at most
      // 2 zeta omega_0 dt of the normal impulse (first order in dt).
      const double omega_0 = std::sqrt(1e6 / (4000 * 4.0 / 3.0 * std::numbers::pi * r * r * r));
      const double bound =
          clip ? 1e-3 : 2 * damping_ratio_for_restitution(e, false) * omega_0 * 1e-7;
      EXPECT_NEAR(impulse_ratio, 1.0, bound);
      EXPECT_NEAR(out.tangential_restitution, expected_et,
                  mu * (1 + e) / std::tan(theta) * bound + 1e-4);
      // The lever to the contact point is R - overlap / 2, so the spin lags by about
      // overlap / (2 R) (< 1 % here).
      EXPECT_NEAR(out.spin, expected_spin, 0.015 * expected_spin);
    }
  }
}

TEST(ContactDynamics, OppositeSpinsHeadOnLeaveSpinsUnchanged) {
  Material m;
  m.restitution = 0.5;
  const double r = 0.01;
  DemWorld world(no_gravity(1e-6));
  const int a = world.add_sphere({-r - 1e-4, 0, 0}, r, m);
  const int b = world.add_sphere({r + 1e-4, 0, 0}, r, m);
  world.set_velocity(a, {0.5, 0, 0});
  world.set_velocity(b, {-0.5, 0, 0});
  // Contact points move together: omega_a x (R e_x) = omega_b x (-R e_x) for opposite spins.
  world.set_angular_velocity(a, {0, 0, 30});
  world.set_angular_velocity(b, {0, 0, -30});
  int touched = 0;
  for (int k = 0; k < 20000; ++k) {
    world.step(1e-6);
    touched += world.contact_count();
  }
  ASSERT_GT(touched, 0);
  EXPECT_LT(world.velocity(a).x(), 0.0);  // rebounded
  EXPECT_NEAR(world.angular_velocity(a).z(), 30, 1e-9);
  EXPECT_NEAR(world.angular_velocity(b).z(), -30, 1e-9);
  EXPECT_NEAR(world.velocity(a).y(), 0, 1e-12);
  EXPECT_NEAR(world.velocity(b).y(), 0, 1e-12);
}

struct InclineResult {
  double acceleration;
  double angular_acceleration;  // about the rolling axis
};

// A body resting on a horizontal plane of two triangles (shared diagonal crossed on the way)
// with gravity tilted by alpha; acceleration measured between 0.05 s and 0.25 s.
InclineResult incline(double alpha_degrees, double mu, bool cylinder) {
  Material m;
  m.normal_stiffness = 1e5;
  m.tangential_stiffness = 4e4;
  m.friction = mu;
  DemParameters p;
  p.gravity = slope_gravity(alpha_degrees);
  p.user_dt = 2e-6;
  DemWorld world(p);
  world.add_triangle({-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, m);
  world.add_triangle({-1, -1, 0}, {1, 1, 0}, {-1, 1, 0}, m);
  const double r = 0.01;
  int body = -1;
  if (cylinder) {
    const double mass = m.density * std::numbers::pi * r * r * 0.05;
    body = world.add_cylinder({-0.3, 0.1, r - mass * -p.gravity.z() / m.normal_stiffness},
                              Eigen::Vector3d::UnitY(), r, 0.05, m);
  } else {
    const double mass = m.density * 4.0 / 3.0 * std::numbers::pi * r * r * r;
    body = world.add_sphere({-0.3, -0.2, r - mass * -p.gravity.z() / m.normal_stiffness}, r, m);
  }
  const auto run_to = [&](double t) {
    while (world.time() < t - 1e-12) world.step(p.user_dt);
  };
  run_to(0.05);
  const double v0 = world.velocity(body).x();
  const double w0 = world.angular_velocity(body).y();
  run_to(0.25);
  return {(world.velocity(body).x() - v0) / 0.2, (world.angular_velocity(body).y() - w0) / 0.2};
}

TEST(ContactDynamics, SphereOnInclineRollsOrSlidesAtTanAlphaVersus3p5Mu) {
  const double g = 9.81;
  const double mu = 0.2;  // rolling without slip while tan(alpha) <= 3.5 mu = 0.7 (35 degrees)
  const double rolling_alpha = 25.0 * std::numbers::pi / 180;
  const InclineResult rolling = incline(25.0, mu, false);
  const double a_roll = 5.0 / 7.0 * g * std::sin(rolling_alpha);
  std::printf("sphere rolling: a %.4f (analytic %.4f) m/s^2\n", rolling.acceleration, a_roll);
  EXPECT_NEAR(rolling.acceleration, a_roll, 0.01 * a_roll);
  EXPECT_NEAR(rolling.angular_acceleration * 0.01, rolling.acceleration, 0.01 * a_roll);

  const double sliding_alpha = 45.0 * std::numbers::pi / 180;
  const InclineResult sliding = incline(45.0, mu, false);
  const double a_slide = g * (std::sin(sliding_alpha) - mu * std::cos(sliding_alpha));
  std::printf("sphere sliding: a %.4f (analytic %.4f), spin-up %.1f (analytic %.1f) rad/s^2\n",
              sliding.acceleration, a_slide, sliding.angular_acceleration,
              5 * mu * g * std::cos(sliding_alpha) / (2 * 0.01));
  EXPECT_NEAR(sliding.acceleration, a_slide, 0.01 * a_slide);
  // Friction mu m g cos(alpha) at lever R spins it up at 5 mu g cos(alpha) / (2 R).
  const double spin = 5 * mu * g * std::cos(sliding_alpha) / (2 * 0.01);
  EXPECT_NEAR(sliding.angular_acceleration, spin, 0.02 * spin);
}

TEST(ContactDynamics, CylinderRollsOnInclineWithTwoThirdsGSinAlpha) {
  // Solid cylinder: rolls while tan(alpha) <= 3 mu; a = 2/3 g sin(alpha).
  const double alpha = 20.0 * std::numbers::pi / 180;
  const InclineResult rolling = incline(20.0, 0.3, true);
  const double expected = 2.0 / 3.0 * 9.81 * std::sin(alpha);
  std::printf("cylinder rolling: a %.4f (analytic %.4f) m/s^2\n", rolling.acceleration, expected);
  EXPECT_NEAR(rolling.acceleration, expected, 0.02 * expected);
  const InclineResult sliding = incline(45.0, 0.2, true);
  const double a_slide = 9.81 * (std::sin(M_PI / 4) - 0.2 * std::cos(M_PI / 4));
  std::printf("cylinder sliding: a %.4f (analytic %.4f) m/s^2\n", sliding.acceleration, a_slide);
  EXPECT_NEAR(sliding.acceleration, a_slide, 0.02 * a_slide);
}

}  // namespace
}  // namespace cosim::dem
