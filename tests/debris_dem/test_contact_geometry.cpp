// Each contact case of seed 004 table 1 against a hand-computed configuration: overlap depth,
// normal direction (from B towards A) and contact point (middle of the overlap).
#include <gtest/gtest.h>

#include <cmath>

#include "cosim/debris_dem/contact_geometry.hpp"
#include "cosim/debris_dem/dem_world.hpp"

namespace cosim::dem {
namespace {

constexpr double kTol = 1e-12;

void expect_vector_near(const Eigen::Vector3d& actual, const Eigen::Vector3d& expected,
                        double tolerance) {
  EXPECT_LT((actual - expected).norm(), tolerance)
      << "actual " << actual.transpose() << " expected " << expected.transpose();
}

TEST(ContactGeometry, SphereSphereCase1) {
  const auto g = sphere_sphere({0.03, 0.04, 0.0}, 0.03, 0.025);
  ASSERT_TRUE(g.touching);
  EXPECT_NEAR(g.overlap, 0.005, kTol);
  expect_vector_near(g.normal, {0.6, 0.8, 0.0}, kTol);
  expect_vector_near(g.point, Eigen::Vector3d(0.6, 0.8, 0.0) * 0.0225, kTol);
  EXPECT_FALSE(sphere_sphere({0.03, 0.04, 0.0}, 0.02, 0.025).touching);
}

TEST(ContactGeometry, SphereCylinderSideCase2) {
  // Cylinder along z, radius 10 mm, length 100 mm; sphere 5 mm at 14 mm from the axis.
  const auto g = sphere_cylinder({0.014, 0.0, 0.02}, 0.005, Eigen::Vector3d::UnitZ(), 0.01, 0.05);
  ASSERT_TRUE(g.touching);
  EXPECT_EQ(g.feature, ContactFeature::kCylinderSide);
  EXPECT_NEAR(g.overlap, 0.001, kTol);
  expect_vector_near(g.normal, Eigen::Vector3d::UnitX(), kTol);
  expect_vector_near(g.point, {0.0095, 0.0, 0.02}, kTol);
}

TEST(ContactGeometry, SphereCylinderBaseFaceCase3_1) {
  const auto g =
      sphere_cylinder({0.003, 0.002, 0.054}, 0.005, Eigen::Vector3d::UnitZ(), 0.01, 0.05);
  ASSERT_TRUE(g.touching);
  EXPECT_EQ(g.feature, ContactFeature::kCylinderBaseFace);
  EXPECT_NEAR(g.overlap, 0.001, kTol);
  expect_vector_near(g.normal, Eigen::Vector3d::UnitZ(), kTol);
  expect_vector_near(g.point, {0.003, 0.002, 0.0495}, kTol);
}

TEST(ContactGeometry, SphereCylinderBaseRimCase3_2) {
  // Rim point Q = (0.01, 0, -0.05) on the lower base; the sphere sits diagonally beyond it.
  const auto g = sphere_cylinder({0.013, 0.0, -0.053}, 0.005, Eigen::Vector3d::UnitZ(), 0.01, 0.05);
  ASSERT_TRUE(g.touching);
  EXPECT_EQ(g.feature, ContactFeature::kCylinderBaseRim);
  const double distance = 0.003 * std::sqrt(2.0);
  EXPECT_NEAR(g.overlap, 0.005 - distance, kTol);
  expect_vector_near(g.normal, Eigen::Vector3d(1.0, 0.0, -1.0).normalized(), kTol);
  expect_vector_near(g.point, Eigen::Vector3d(0.01, 0, -0.05) - 0.5 * g.overlap * g.normal, kTol);
}

TEST(ContactGeometry, SphereCylinderTiltedAxisMatchesRotatedCase) {
  // Same side contact with the cylinder along (1,1,0)/sqrt2: the result rotates with it.
  const Eigen::Quaterniond q =
      Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), Eigen::Vector3d(1, 1, 0));
  const auto g = sphere_cylinder(q * Eigen::Vector3d(0.014, 0.0, 0.02), 0.005,
                                 q * Eigen::Vector3d::UnitZ(), 0.01, 0.05);
  ASSERT_TRUE(g.touching);
  EXPECT_NEAR(g.overlap, 0.001, 1e-12);
  expect_vector_near(g.normal, q * Eigen::Vector3d::UnitX(), 1e-12);
}

TEST(ContactGeometry, SphereTriangleFaceEdgeVertexCase4) {
  const Eigen::Vector3d e1(1, 0, 0);
  const Eigen::Vector3d e2(0, 1, 0);
  const Eigen::Vector3d n = Eigen::Vector3d::UnitZ();
  const auto face = sphere_triangle({0.2, 0.2, 0.004}, 0.005, e1, e2, n);
  ASSERT_TRUE(face.touching);
  EXPECT_EQ(face.feature, ContactFeature::kTriangleFace);
  EXPECT_NEAR(face.overlap, 0.001, kTol);
  expect_vector_near(face.normal, n, kTol);
  expect_vector_near(face.point, {0.2, 0.2, -0.0005}, kTol);
  // Below the triangle: two-sided, the normal flips.
  const auto below = sphere_triangle({0.2, 0.2, -0.004}, 0.005, e1, e2, n);
  expect_vector_near(below.normal, -n, kTol);

  const auto edge = sphere_triangle({0.5, -0.003, 0.003}, 0.005, e1, e2, n);
  ASSERT_TRUE(edge.touching);
  EXPECT_EQ(edge.feature, ContactFeature::kTriangleEdge);
  EXPECT_EQ(edge.index, 0);
  EXPECT_NEAR(edge.overlap, 0.005 - 0.003 * std::sqrt(2.0), kTol);
  expect_vector_near(edge.normal, Eigen::Vector3d(0, -1, 1).normalized(), kTol);

  const auto vertex = sphere_triangle({-0.002, -0.002, 0.002}, 0.005, e1, e2, n);
  ASSERT_TRUE(vertex.touching);
  EXPECT_EQ(vertex.feature, ContactFeature::kTriangleVertex);
  EXPECT_EQ(vertex.index, 0);
  EXPECT_NEAR(vertex.overlap, 0.005 - 0.002 * std::sqrt(3.0), kTol);
  expect_vector_near(vertex.normal, Eigen::Vector3d(-1, -1, 1).normalized(), kTol);
}

TEST(ContactGeometry, CylinderSideSideCrossingCase5) {
  const auto g = cylinder_cylinder({0, 0, 0.018}, Eigen::Vector3d::UnitX(), 0.01, 0.05,
                                   Eigen::Vector3d::UnitY(), 0.01, 0.05);
  ASSERT_TRUE(g.touching);
  EXPECT_EQ(g.feature, ContactFeature::kSideSide);
  EXPECT_NEAR(g.overlap, 0.002, 1e-12);
  expect_vector_near(g.normal, Eigen::Vector3d::UnitZ(), 1e-12);
  expect_vector_near(g.point, {0, 0, 0.009}, 1e-12);
}

TEST(ContactGeometry, CylinderSideSideParallelAxesCase5) {
  // Parallel logs offset 20 mm along the axis: contact at the middle of the common part.
  const auto g = cylinder_cylinder({0.02, 0, 0.019}, Eigen::Vector3d::UnitX(), 0.01, 0.05,
                                   Eigen::Vector3d::UnitX(), 0.01, 0.05);
  ASSERT_TRUE(g.touching);
  EXPECT_EQ(g.feature, ContactFeature::kSideSide);
  EXPECT_NEAR(g.overlap, 0.001, 1e-12);
  expect_vector_near(g.normal, Eigen::Vector3d::UnitZ(), 1e-12);
  expect_vector_near(g.point, {0.01, 0, 0.0095}, 1e-12);
  // Antiparallel axes give the same answer.
  const auto anti = cylinder_cylinder({0.02, 0, 0.019}, -Eigen::Vector3d::UnitX(), 0.01, 0.05,
                                      Eigen::Vector3d::UnitX(), 0.01, 0.05);
  EXPECT_NEAR(anti.overlap, 0.001, 1e-12);
  expect_vector_near(anti.point, {0.01, 0, 0.0095}, 1e-12);
}

TEST(ContactGeometry, CylinderBaseRimOnSideCase6) {
  // Log A tilted 45 degrees in the x-z plane; the lowest rim point of its lower base sits 0.5 mm
  // inside the side of log B (along y, radius 10 mm), directly above B's axis.
  const Eigen::Vector3d a = Eigen::Vector3d(1, 0, 1).normalized();
  const Eigen::Vector3d down_rim = Eigen::Vector3d(1, 0, -1).normalized();
  const Eigen::Vector3d lowest(0, 0, 0.0095);
  const Eigen::Vector3d center = lowest - 0.01 * down_rim + 0.05 * a;
  const auto g = cylinder_cylinder(center, a, 0.01, 0.05, Eigen::Vector3d::UnitY(), 0.01, 0.05);
  ASSERT_TRUE(g.touching);
  EXPECT_NEAR(g.overlap, 0.0005, 1e-9);
  expect_vector_near(g.normal, Eigen::Vector3d::UnitZ(), 1e-9);
  expect_vector_near(g.point, {0, 0, 0.00975}, 1e-9);
}

TEST(ContactGeometry, CylinderBaseBaseCase7) {
  // Coaxial logs end to end, 1 mm overlap, A offset 4 mm sideways.
  const auto g = cylinder_cylinder({0.004, 0, 0.099}, Eigen::Vector3d::UnitZ(), 0.01, 0.05,
                                   Eigen::Vector3d::UnitZ(), 0.01, 0.05);
  ASSERT_TRUE(g.touching);
  EXPECT_EQ(g.feature, ContactFeature::kBaseBase);
  EXPECT_NEAR(g.overlap, 0.001, 1e-12);
  expect_vector_near(g.normal, Eigen::Vector3d::UnitZ(), 1e-12);
  EXPECT_NEAR(g.point.z(), 0.0495, 1e-12);
  EXPECT_FALSE(cylinder_cylinder({0.025, 0, 0.099}, Eigen::Vector3d::UnitZ(), 0.01, 0.05,
                                 Eigen::Vector3d::UnitZ(), 0.01, 0.05)
                   .touching);
}

TEST(ContactGeometry, CylinderBaseOnTriangleCase8) {
  // Column tilted 30 degrees from vertical; its lowest rim point is 1 mm below the triangle.
  const Eigen::Vector3d a(std::sin(M_PI / 6), 0, std::cos(M_PI / 6));
  const Eigen::Vector3d rim_dir = Eigen::Vector3d(std::cos(M_PI / 6), 0, -std::sin(M_PI / 6));
  // Lower base center B = c - h a; lowest rim point = B - r (perpendicular of z) = B + r rim_dir.
  const Eigen::Vector3d lowest(0.3, 0.3, -0.001);
  const Eigen::Vector3d center = lowest - 0.01 * rim_dir + 0.05 * a;
  const auto g =
      cylinder_triangle(center, a, 0.01, 0.05, {1, 0, 0}, {0, 1, 0}, Eigen::Vector3d::UnitZ());
  ASSERT_TRUE(g.touching);
  EXPECT_EQ(g.feature, ContactFeature::kBaseTriangle);
  EXPECT_NEAR(g.overlap, 0.001, 1e-12);
  expect_vector_near(g.normal, Eigen::Vector3d::UnitZ(), 1e-12);
  expect_vector_near(g.point, {0.3, 0.3, -0.0005}, 1e-12);
}

TEST(ContactGeometry, CylinderSideOnTriangle) {
  const auto g = cylinder_triangle({0.5, 0.3, 0.009}, Eigen::Vector3d::UnitX(), 0.01, 0.05,
                                   {1, 0, 0}, {0, 1, 0}, Eigen::Vector3d::UnitZ());
  ASSERT_TRUE(g.touching);
  EXPECT_EQ(g.feature, ContactFeature::kSideTriangle);
  EXPECT_NEAR(g.overlap, 0.001, 1e-12);
  expect_vector_near(g.normal, Eigen::Vector3d::UnitZ(), 1e-12);
  expect_vector_near(g.point, {0.5, 0.3, -0.0005}, 1e-12);
  // Log hanging over the hypotenuse (x + y = 1): contact centred on the part over the triangle.
  const auto half = cylinder_triangle({0.7, 0.3, 0.009}, Eigen::Vector3d::UnitX(), 0.01, 0.05,
                                      {1, 0, 0}, {0, 1, 0}, Eigen::Vector3d::UnitZ());
  ASSERT_TRUE(half.touching);
  EXPECT_NEAR(half.point.x(), 0.675, 1e-12);
  // Beside the triangle (beyond the hypotenuse by more than the radius): no contact.
  EXPECT_FALSE(cylinder_triangle({0.7, 0.5, 0.009}, Eigen::Vector3d::UnitX(), 0.01, 0.05, {1, 0, 0},
                                 {0, 1, 0}, Eigen::Vector3d::UnitZ())
                   .touching);
}

// Net contact force on a resting sphere after one step with zero velocity (no damping force):
// F = m dv / dt.
Eigen::Vector3d contact_force(DemWorld& world, int sphere, double dt) {
  world.step(dt);
  return world.mass(sphere) * world.velocity(sphere) / dt;
}

DemParameters no_gravity() {
  DemParameters p;
  p.gravity.setZero();
  return p;
}

TEST(ContactGeometry, SphereOnSharedMeshEdgeAndVertexCountsOnce) {
  Material m;
  const double r = 0.01;
  const double overlap = 0.001;
  const std::vector<Eigen::Vector3d> positions{
      {0.5, 0.5, r - overlap},    // on the shared diagonal edge
      {0.0, 0.0, r - overlap},    // on the vertex shared by both triangles
      {0.5, 0.503, r - overlap},  // over one face, 2 mm from the shared edge
      {0.999, 0.5, r - overlap},  // over a face near a free boundary edge
  };
  for (const auto& p : positions) {
    DemWorld world(no_gravity());
    world.add_triangle({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, m);
    world.add_triangle({0, 0, 0}, {1, 1, 0}, {0, 1, 0}, m);
    const int s = world.add_sphere(p, r, m);
    const Eigen::Vector3d f = contact_force(world, s, 1e-7);
    EXPECT_EQ(world.contact_count(), 1) << "sphere at " << p.transpose();
    EXPECT_NEAR(f.z(), m.normal_stiffness * overlap, 1e-6) << "sphere at " << p.transpose();
  }
}

TEST(ContactGeometry, SphereOnFanVertexAndInConcaveCorner) {
  Material m;
  const double r = 0.01;
  {
    // Six triangles around a vertex; sphere over one of them close to the vertex.
    DemWorld world(no_gravity());
    for (int k = 0; k < 6; ++k) {
      const double a0 = k * M_PI / 3;
      const double a1 = (k + 1) * M_PI / 3;
      world.add_triangle({0, 0, 0}, {std::cos(a0), std::sin(a0), 0},
                         {std::cos(a1), std::sin(a1), 0}, m);
    }
    const int s = world.add_sphere({0.004, 0.001, r - 0.001}, r, m);
    const Eigen::Vector3d f = contact_force(world, s, 1e-7);
    EXPECT_EQ(world.contact_count(), 1);
    EXPECT_NEAR(f.z(), 10.0, 1e-6);
  }
  {
    // Bed and wall meeting at a shared edge: a sphere in the corner touches both.
    DemWorld world(no_gravity());
    world.add_triangle({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, m);
    world.add_triangle({0, 0, 0}, {1, 1, 0}, {0, 1, 0}, m);
    world.add_triangle({0, 0, 0}, {1, 0, 0}, {1, 0, 1}, m);
    world.add_triangle({0, 0, 0}, {1, 0, 1}, {0, 0, 1}, m);
    const int s = world.add_sphere({0.5, r - 0.001, r - 0.002}, r, m);
    const Eigen::Vector3d f = contact_force(world, s, 1e-7);
    EXPECT_EQ(world.contact_count(), 2);
    EXPECT_NEAR(f.y(), 10.0, 1e-6);
    EXPECT_NEAR(f.z(), 20.0, 1e-6);
  }
}

}  // namespace
}  // namespace cosim::dem
