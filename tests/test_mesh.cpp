#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

#include "isochor/base/error.hpp"
#include "isochor/core/meshing.hpp"
#include "test_util.hpp"

using namespace isochor;

using test::expect_closed_outward;

TEST(Mesh, BoxVolumeIsExactForBothSplits) {
  for (int split : {5, 6}) {
    Mesh m = make_box(Eigen::Vector3d(2.0, 0.5, 1.5), {3, 4, 5}, Eigen::Vector3d(1, 2, 3), split);
    EXPECT_EQ(m.num_tets(), 3 * 4 * 5 * split);
    EXPECT_EQ(m.num_nodes(), 4 * 5 * 6);
    EXPECT_NEAR(m.rest_volume(), 1.5, 1e-14);
    EXPECT_EQ(m.reoriented_tets(), 0);  // the generator writes positive tets
    expect_closed_outward(m);
    // Every cell's surface is two triangles per boundary face of the box.
    EXPECT_EQ(m.surface().size(), 2u * 2 * (3 * 4 + 4 * 5 + 3 * 5));
    if (split == 6) {
      for (double v : m.rest_volumes()) EXPECT_NEAR(v, 1.5 / 360.0, 1e-15);
    }
  }
}

TEST(Mesh, FiveSplitTetVolumes) {
  // Unit cells: four corner tets of 1/6 and a central tet of 1/3.
  Mesh m = make_box(Eigen::Vector3d::Ones() * 2, {2, 2, 2}, Eigen::Vector3d::Zero(), 5);
  int corners = 0, centres = 0;
  for (double v : m.rest_volumes()) {
    if (std::abs(v - 1.0 / 6.0) < 1e-14) corners++;
    if (std::abs(v - 1.0 / 3.0) < 1e-14) centres++;
  }
  EXPECT_EQ(corners, 32);
  EXPECT_EQ(centres, 8);
}

TEST(Mesh, KuhnSplitInteriorVertexHasKnownRings) {
  // In the Freudenthal-Kuhn triangulation every interior vertex has 14 edge neighbours and 24 tets.
  Mesh m = make_box(Eigen::Vector3d::Ones(), {4, 4, 4}, Eigen::Vector3d::Zero(), 6);
  const int centre = 2 + 5 * (2 + 5 * 2);
  EXPECT_EQ(m.node_ring(centre, 1).size(), 15u);
  EXPECT_EQ(m.tet_ring(centre, 1).size(), 24u);
  EXPECT_EQ(m.node_ring(centre, 0), std::vector<int>{centre});
  // The 2-ring of the Kuhn lattice: points p with max(|p|, |p_a - p_b|) <= 2 in lattice norm.
  int expected = 0;
  for (int i = -2; i <= 2; ++i)
    for (int j = -2; j <= 2; ++j)
      for (int k = -2; k <= 2; ++k) {
        // Graph distance in the Kuhn lattice (edges along e_a, e_a+e_b, e_1+e_2+e_3 sums of positive
        // or negative steps): max(positive part) + max(negative part) of the coordinates.
        int pos = std::max({i, j, k, 0}), neg = -std::min({i, j, k, 0});
        if (pos + neg <= 2) expected++;
      }
  EXPECT_EQ(static_cast<int>(m.node_ring(centre, 2).size()), expected);
  // tet_ring(k=2): every tet touching a node of the 1-ring.
  std::vector<int> t2 = m.tet_ring(centre, 2);
  for (int v : m.node_ring(centre, 1))
    for (const int* e = m.node_tets().begin(v); e != m.node_tets().end(v); ++e)
      EXPECT_TRUE(std::binary_search(t2.begin(), t2.end(), *e));
}

TEST(Mesh, ReversedTetIsReorderedAndFlatTetRejected) {
  Points x(3, 5);
  x << 0, 1, 0, 0, 1,  //
      0, 0, 1, 0, 1,   //
      0, 0, 0, 1, 1;
  // Tet 1 is given with negative orientation.
  Mesh m(x, {{0, 1, 2, 3}, {1, 3, 2, 4}}, "two");
  EXPECT_EQ(m.reoriented_tets(), 1);
  EXPECT_NEAR(m.rest_volumes()[0], 1.0 / 6.0, 1e-15);
  EXPECT_NEAR(m.rest_volumes()[1], 1.0 / 3.0, 1e-15);
  for (const Tet& t : m.tets()) EXPECT_GT(tet_signed_volume(x.col(t[0]), x.col(t[1]), x.col(t[2]), x.col(t[3])), 0.0);
  expect_closed_outward(m);

  Points y = x;
  y.col(4) = Eigen::Vector3d(0.5, 0.5, 0.0);  // tet (1, 2, 0, 4) lies in z = 0
  std::string msg = test::error_of([&] { Mesh(y, {{0, 1, 2, 3}, {1, 2, 0, 4}}, "flat"); });
  EXPECT_NE(msg.find("flat: tet 1 is degenerate"), std::string::npos) << msg;
}

TEST(Mesh, SurfaceCheckFindsHoles) {
  Mesh m = make_box(Eigen::Vector3d::Ones(), {2, 2, 2}, Eigen::Vector3d::Zero(), 6);
  std::vector<Tri> s = m.surface();
  s.pop_back();
  SurfaceCheck c = check_surface(s);
  EXPECT_FALSE(c.closed);
  EXPECT_EQ(c.boundary_edges, 3);
  EXPECT_EQ(c.euler_characteristic, 1);
}

TEST(Mesh, UnusedNodesAreRemoved) {
  Points x(3, 6);
  x << 9, 0, 1, 0, 0, 7,  //
      9, 0, 0, 1, 0, 7,   //
      9, 0, 0, 0, 1, 7;
  std::vector<Tet> tets{{1, 2, 3, 4}};
  std::map<std::string, std::vector<int>> sets{{"s", {0, 2, 5}}};
  compact_unused_nodes(x, tets, &sets);
  EXPECT_EQ(x.cols(), 4);
  EXPECT_EQ(tets[0], (Tet{0, 1, 2, 3}));
  EXPECT_EQ(sets["s"], std::vector<int>{1});
}

// The smallest interior angle of a tet's four faces, in degrees.
static double min_face_angle(const Points& x, const Tet& t) {
  static constexpr int kFaces[4][3] = {{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}};
  double smallest = 180;
  for (const auto& f : kFaces)
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector3d a = x.col(t[f[(c + 1) % 3]]) - x.col(t[f[c]]),
                            b = x.col(t[f[(c + 2) % 3]]) - x.col(t[f[c]]);
      smallest = std::min(smallest, std::atan2(a.cross(b).norm(), a.dot(b)) * 180 / M_PI);
    }
  return smallest;
}

TEST(Mesh, SliverBoxKeepsItsSizeAndHasTheAnglesItPromises) {
  // Layers alternate thick (w) and thin (w / 60): 3 thick + 2 thin = size, so w = 1 / (3 + 2 / 60).
  const double r = 60;
  Mesh m = make_box(Eigen::Vector3d::Ones(), {5, 5, 5}, Eigen::Vector3d::Zero(), 6, r);
  EXPECT_NEAR(m.rest_volume(), 1.0, 1e-13);
  EXPECT_EQ(m.reoriented_tets(), 0);
  expect_closed_outward(m);
  const Points& X = m.rest_positions();
  EXPECT_NEAR(X.row(0).minCoeff(), -0.5, 1e-15);
  EXPECT_NEAR(X.row(0).maxCoeff(), 0.5, 1e-15);
  const double w = 1.0 / (3.0 + 2.0 / r);
  // The second node along x sits one thick layer in, the third one thin layer further.
  EXPECT_NEAR(X(0, 1) - X(0, 0), w, 1e-15);
  EXPECT_NEAR(X(0, 2) - X(0, 1), w / r, 1e-15);
  // A Kuhn tet of a cell thin in one axis and thick in the others has a right-angled face with legs
  // sqrt(2) w (the diagonal of the thick face) and w / r: its smallest angle is atan(1 / (sqrt(2) r))
  // = 0.675 degrees, and no face is flatter than that.
  double smallest = 180, largest_ratio = 0;
  for (const Tet& t : m.tets()) {
    smallest = std::min(smallest, min_face_angle(X, t));
    double lo = 1e300, hi = 0;
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) {
        const double l = (X.col(t[a]) - X.col(t[b])).norm();
        lo = std::min(lo, l), hi = std::max(hi, l);
      }
    largest_ratio = std::max(largest_ratio, hi / lo);
  }
  EXPECT_NEAR(smallest, std::atan(1 / (std::sqrt(2.0) * r)) * 180 / M_PI, 1e-9);
  EXPECT_LT(smallest, 1.0);
  // The longest edge of a thin-thick-thick cell's tet is its diagonal sqrt(2 w^2 + (w/r)^2), the
  // shortest w / r: ratio sqrt(2 r^2 + 1) = 84.9.
  EXPECT_NEAR(largest_ratio, std::sqrt(2 * r * r + 1), 1e-9);
  // sliver_ratio = 1 is the regular grid, node for node.
  Mesh a = make_box(Eigen::Vector3d(2, 1, 3), {3, 4, 5}, Eigen::Vector3d(1, 2, 3), 6);
  Mesh b = make_box(Eigen::Vector3d(2, 1, 3), {3, 4, 5}, Eigen::Vector3d(1, 2, 3), 6, 1.0);
  EXPECT_EQ((a.rest_positions() - b.rest_positions()).norm(), 0.0);
  EXPECT_THROW(make_box(Eigen::Vector3d::Ones(), {2, 2, 2}, Eigen::Vector3d::Zero(), 6, 0.5), Error);
}

TEST(Mesh, RestShapeErrorIsZeroForARigidMotionAndMeasuresTheRest) {
  Mesh m = make_box(Eigen::Vector3d(2, 1, 0.5), {4, 2, 2}, Eigen::Vector3d::Zero(), 6);
  const Points& X = m.rest_positions();
  const double diag = std::sqrt(4.0 + 1.0 + 0.25);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  const Points moved = (R * X).colwise() + Eigen::Vector3d(3, -1, 7);
  EXPECT_LT(rest_shape_error(X, moved), 1e-14);
  // One node pushed 0.1 away, the others in place: the fit moves a little, the error is about 0.1.
  Points bumped = X;
  bumped(2, 0) += 0.1;
  EXPECT_NEAR(rest_shape_error(X, bumped) * diag, 0.1, 0.01);
  // Scaled by 1.1 about the centroid: the farthest node (a corner, half a diagonal out) is 0.05 diag away.
  const Points scaled = 1.1 * X;
  EXPECT_NEAR(rest_shape_error(X, scaled), 0.05, 1e-12);
  // Its rms: 0.1 times the nodes' rms distance from the centroid (X's centroid is 0), over diag.
  const double rms = std::sqrt(X.colwise().squaredNorm().mean());
  EXPECT_NEAR(rest_shape_distance(X, scaled).rms, 0.1 * rms / diag, 1e-12);
  EXPECT_EQ(rest_shape_distance(X, scaled).largest, rest_shape_error(X, scaled));
  // A mirror image is not a rigid motion.
  Points mirrored = X;
  mirrored.row(0) *= -1;
  EXPECT_GT(rest_shape_error(X, mirrored), 0.1);
}
