#include <gtest/gtest.h>

#include <cmath>

#include "isochor/core/meshing.hpp"
#include "test_util.hpp"

using namespace isochor;

using test::expect_closed_outward;

TEST(Shapes, SphereVolumeWithinTwoPercentAndConverging) {
  const double r = 0.1, exact = 4.0 / 3.0 * M_PI * r * r * r;
  double previous = 1.0;
  std::vector<double> errors;
  for (long target : {1000L, 5000L, 20000L}) {
    Mesh m = make_sphere(r, 0.0, target, Eigen::Vector3d(0, 0, 0.2));
    expect_closed_outward(m);
    const double err = std::abs(m.rest_volume() - exact) / exact;
    if (target == 5000) {
      EXPECT_LT(err, 0.02);
    }  // the default resolution
    EXPECT_LT(err, previous);
    previous = err;
    errors.push_back(err);
    // An inscribed polyhedron: every node within the ball, surface nodes on the sphere.
    for (int v : m.surface_nodes())
      EXPECT_NEAR((m.rest_positions().col(v) - Eigen::Vector3d(0, 0, 0.2)).norm(), r, 1e-9);
    // The target count is met within 15%.
    EXPECT_NEAR(m.num_tets() / static_cast<double>(target), 1.0, 0.15) << target;
  }
  // Second-order convergence of the inscribed surface: error ~ h^2 ~ N^(-2/3). From 1000 to 20000 tets
  // the error falls by 20^(2/3) = 7.4; ask for at least 4.
  EXPECT_GT(errors.front() / errors.back(), 4.0);
}

TEST(Shapes, CylinderVolumeWithinTwoPercentAndConverging) {
  const double r = 0.5, h = 1.0, exact = M_PI * r * r * h;
  double previous = 1.0;
  for (int res : {12, 24, 48}) {
    Mesh m = make_cylinder(r, h, res, Eigen::Vector3d::Zero());
    expect_closed_outward(m);
    const double err = std::abs(m.rest_volume() - exact) / exact;
    if (res == 24) {
      EXPECT_LT(err, 0.02);
    }
    EXPECT_LT(err, previous);
    if (res == 48) {
      EXPECT_LT(err, previous / 3.0);
    }  // second order: halving h quarters the error
    previous = err;
    EXPECT_FALSE(m.node_sets.at("bottom").empty());
    for (int v : m.node_sets.at("top")) EXPECT_NEAR(m.rest_positions()(2, v), 0.5, 1e-12);
  }
}

TEST(Shapes, TwoTetsHaveEqualVolumesSharingAFace) {
  Mesh m = make_two_tets(1.0);
  ASSERT_EQ(m.num_tets(), 2);
  const double regular = 1.0 / (6.0 * std::sqrt(2.0));  // volume of a regular tet of edge 1
  EXPECT_NEAR(m.rest_volumes()[0], regular, 1e-15);
  EXPECT_NEAR(m.rest_volumes()[1], regular, 1e-15);
  EXPECT_EQ(m.surface().size(), 6u);
  expect_closed_outward(m);
}
