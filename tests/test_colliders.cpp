// Rigid colliders: every shape's signed distance against its closed form and its gradient and
// Hessian against central differences; the contact's energy, damping and friction against
// central differences on moving and turning colliders; a collider's pose against the motion of
// the mesh nodes its driver or bone moves.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <functional>
#include <fstream>
#include <map>
#include <random>

#include "isochor/models/colliders.hpp"
#include "isochor/models/forces.hpp"
#include "isochor/models/material.hpp"
#include "isochor/core/meshing.hpp"
#include "isochor/models/self_contact.hpp"
#include "isochor/core/paint.hpp"
#include <limits>
#include <sstream>
#include "isochor/core/output_reader.hpp"
#include "isochor/app/run.hpp"
#include "isochor/scene/scene.hpp"
#include "test_util.hpp"

using namespace isochor;

namespace {

// Central differences of a value and its gradient (3 components) against the gradient and Hessian.
void check_fd(const std::function<double(const Vec3&, Vec3*, Mat3*)>& f, const Vec3& x, const std::string& what,
              double tol = 1e-6) {
  Vec3 g, gfd;
  Mat3 H, Hfd;
  f(x, &g, &H);
  const double h = 1e-6;
  for (int k = 0; k < 3; ++k) {
    Vec3 xp = x, xm = x, gp, gm;
    xp[k] += h;
    xm[k] -= h;
    gfd[k] = (f(xp, &gp, nullptr) - f(xm, &gm, nullptr)) / (2 * h);
    Hfd.col(k) = (gp - gm) / (2 * h);
  }
  EXPECT_LT((g - gfd).norm(), tol * std::max(1.0, gfd.norm())) << what << " at " << x.transpose();
  EXPECT_LT((H - Hfd).norm(), tol * std::max(1.0, Hfd.norm())) << what << " at " << x.transpose();
}

// An icosahedron subdivided `levels` times (each triangle into four), its vertices on the sphere
// of radius R about the origin; outward oriented.
void icosphere(double R, int levels, Points& x, std::vector<Tri>& tris) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<Vec3> v = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                         {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  tris = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
          {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
          {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (Vec3& p : v) p.normalize();
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto middle = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      return mid[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<Tri> finer;
    for (const Tri& T : tris) {
      const int a = middle(T[0], T[1]), b = middle(T[1], T[2]), c = middle(T[2], T[0]);
      finer.insert(finer.end(), {Tri{T[0], a, c}, Tri{T[1], b, a}, Tri{T[2], c, b}, Tri{a, b, c}});
    }
    tris = finer;
  }
  x.resize(3, static_cast<Eigen::Index>(v.size()));
  for (std::size_t i = 0; i < v.size(); ++i) x.col(i) = R * v[i];
}

// The surface of the box |x_i| <= half_i: 8 corners, 12 outward triangles.
void box_surface(const Vec3& half, Points& x, std::vector<Tri>& tris) {
  x.resize(3, 8);
  for (int c = 0; c < 8; ++c) x.col(c) = Vec3(c & 4 ? 1 : -1, c & 2 ? 1 : -1, c & 1 ? 1 : -1).cwiseProduct(half);
  const int faces[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
  tris.clear();
  for (const auto& q : faces) tris.insert(tris.end(), {Tri{q[0], q[1], q[2]}, Tri{q[0], q[2], q[3]}});
}

std::shared_ptr<const MeshSdf> sphere_sdf(double R, double cell) {
  Points x;
  std::vector<Tri> tris;
  icosphere(R, 4, x, tris);
  return std::make_shared<const MeshSdf>(x, tris, cell, 0.05, "icosphere");
}

// A collider of every shape, placed off the origin and turned.
std::vector<Collider> shapes() {
  std::vector<Collider> all;
  auto add = [&](ColliderShape s) {
    Collider c;
    c.shape = s;
    c.name = s.name();
    c.center = Vec3(0.1, -0.2, 0.3);
    c.rotation = frame_with_axis(Vec3(0.3, 0.4, 1.0), 0.7);
    all.push_back(c);
  };
  using K = ColliderShape::Kind;
  add({K::plane});
  add({K::sphere, 0.2});
  add({K::capsule, 0.1, 0.15});
  add({K::box, 0, 0, Vec3(0.2, 0.1, 0.15), 0.03});
  add({K::cylinder, 0.2, 0.1, Vec3::Zero(), 0.02});         // solid
  add({K::cylinder, 0.2, 0.05, Vec3::Zero(), 0.01, 0.04});  // hollow: a band
  ColliderShape mesh{K::mesh};
  mesh.mesh = sphere_sdf(0.2, 0.02);
  add(mesh);
  return all;
}

// Random world points within `band` of the collider's surface (by rejection on the distance).
std::vector<Vec3> near_surface(const Collider& c, const ColliderPose& P, double band, int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  const double R = std::isfinite(c.shape.bound()) ? c.shape.bound() + band : 0.5;
  std::vector<Vec3> pts;
  while (static_cast<int>(pts.size()) < count) {
    const Vec3 x = P.b + R * Vec3(u(rng), u(rng), u(rng));
    if (std::abs(c.distance(P, x, nullptr, nullptr)) < band) pts.push_back(x);
  }
  return pts;
}

}  // namespace

TEST(Colliders, DistancesMatchTheirClosedForms) {
  using K = ColliderShape::Kind;
  const ColliderShape sphere{K::sphere, 0.2}, capsule{K::capsule, 0.1, 0.15},
      box{K::box, 0, 0, Vec3(0.2, 0.1, 0.15), 0.03}, cyl{K::cylinder, 0.2, 0.1, Vec3::Zero(), 0.02},
      band{K::cylinder, 0.2, 0.05, Vec3::Zero(), 0.01, 0.04};
  EXPECT_NEAR(sphere.distance(Vec3(0.3, 0.4, 0), nullptr, nullptr), 0.5 - 0.2, 1e-15);
  EXPECT_NEAR(sphere.distance(Vec3(0.0, 0.0, 0.05), nullptr, nullptr), -0.15, 1e-15);
  EXPECT_NEAR(capsule.distance(Vec3(0.3, 0.4, 0.1), nullptr, nullptr), 0.5 - 0.1, 1e-15);       // beside the segment
  EXPECT_NEAR(capsule.distance(Vec3(0, 0.3, 0.15 + 0.4), nullptr, nullptr), 0.5 - 0.1, 1e-15);  // beyond its end
  EXPECT_NEAR(box.distance(Vec3(0.05, 0.02, 0.15 + 0.07), nullptr, nullptr), 0.07, 1e-15);      // above a face
  EXPECT_NEAR(box.distance(Vec3(0.05, 0.02, 0.15 - 0.01), nullptr, nullptr), -0.01, 1e-15);     // just inside it
  // Beyond a rounded edge: the distance to the inner box's edge minus the rounding radius.
  EXPECT_NEAR(box.distance(Vec3(0.2 + 0.03, 0.0, 0.15 + 0.04), nullptr, nullptr), std::hypot(0.06, 0.07) - 0.03, 1e-15);
  EXPECT_NEAR(cyl.distance(Vec3(0.3, 0.4, 0.0), nullptr, nullptr), 0.5 - 0.2, 1e-15);
  EXPECT_NEAR(cyl.distance(Vec3(0.01, 0.02, 0.1 + 0.3), nullptr, nullptr), 0.3, 1e-15);
  // The band: tissue in its hole is outside (positive), at the hole's radius distance 0, and the
  // wall is solid; above the band there is nothing near the axis.
  EXPECT_NEAR(band.distance(Vec3(0, 0, 0), nullptr, nullptr), 0.2, 1e-15);
  EXPECT_NEAR(band.distance(Vec3(0.06, 0.08, 0.01), nullptr, nullptr), 0.2 - 0.1, 1e-15);
  EXPECT_NEAR(band.distance(Vec3(0.22, 0, 0.0), nullptr, nullptr), -0.02, 1e-15);  // in the middle of the wall
  EXPECT_NEAR(band.distance(Vec3(0.3, 0, 0.0), nullptr, nullptr), 0.3 - 0.24, 1e-15);
  EXPECT_NEAR(band.distance(Vec3(0.0, 0.1, 0.4), nullptr, nullptr), std::hypot(0.2 + 0.01 - 0.1, 0.4 - 0.04) - 0.01,
              1e-15);
}

TEST(Colliders, GradientAndHessianOfEveryShapeAgainstFiniteDifferences) {
  for (const Collider& c : shapes()) {
    const ColliderPose P = c.pose(0.0, nullptr);
    for (const Vec3& x : near_surface(c, P, 0.02, 40, 3)) {
      check_fd([&](const Vec3& y, Vec3* g, Mat3* H) { return c.distance(P, y, g, H); }, x, c.name, 1e-5);
      Vec3 g;
      c.distance(P, x, &g, nullptr);
      if (c.shape.kind != ColliderShape::Kind::mesh) {  // (a mesh's is a smoothed distance)
        EXPECT_NEAR(g.norm(), 1.0, 1e-12) << c.name;    // a distance: |grad s| = 1
      }
    }
  }
}

TEST(Colliders, ContactEnergyDampingAndFrictionAgainstFiniteDifferences) {
  // Each shape turning about an axis and moving, with damping and friction.
  const double k = 3e4, delta = 0.01;
  for (Collider c : shapes()) {
    c.law = ContactLaw{k, delta, false, 0.4, 0.6, 0.05};
    c.motion = Driver{};
    c.motion.kind = Driver::Kind::keyframes_cubic;
    c.motion.rotation = true;
    c.motion.axis = Vec3(1, -1, 2).normalized();
    c.motion.center = Vec3(0.2, 0.1, 0);
    c.motion.times = {0.0, 1.0, 2.0};
    c.motion.values = {Vec3::Zero(), Vec3(0.8, 0, 0), Vec3(0.3, 0, 0)};
    const ColliderPose P = c.pose(0.6, nullptr);
    ASSERT_GT(P.omega.norm(), 0.1);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1, 1);
    for (const Vec3& x : near_surface(c, P, delta, 20, 9)) {
      if (c.distance(P, x, nullptr, nullptr) > 0.9 * delta) continue;
      check_fd(
          [&](const Vec3& y, Vec3* g, Mat3* H) {
            Vec3 n;
            Mat3 Hs;
            const double s = c.distance(P, y, &n, &Hs);
            return contact_energy(k, delta, s, n, Hs, g, H);
          },
          x, std::string(c.name) + " energy", 1e-5);
      const Vec3 v(u(rng), u(rng), u(rng));
      auto force = [&](const Vec3& y, const Vec3& vy, Mat3* Dx, Mat3* Dv) {
        Vec3 n;
        Mat3 Hs;
        const double s = c.distance(P, y, &n, &Hs);
        return contact_damping_force(k, c.law.damping, c.law.friction, c.law.slip_speed, delta, s, n, Hs,
                                     vy - P.velocity_at(y), -skew(P.omega), Dx, Dv);
      };
      Mat3 Dx, Dv, Dx_fd, Dv_fd;
      force(x, v, &Dx, &Dv);
      const double h = 1e-7;
      for (int j = 0; j < 3; ++j) {
        const Vec3 e = h * Vec3::Unit(j);
        Dx_fd.col(j) = -(force(x + e, v, nullptr, nullptr) - force(x - e, v, nullptr, nullptr)) / (2 * h);
        Dv_fd.col(j) = -(force(x, v + e, nullptr, nullptr) - force(x, v - e, nullptr, nullptr)) / (2 * h);
      }
      EXPECT_LT((Dx - Dx_fd).norm(), 1e-5 * std::max(1.0, Dx_fd.norm())) << c.name << " -df/dx at " << x.transpose();
      EXPECT_LT((Dv - Dv_fd).norm(), 1e-5 * std::max(1.0, Dv_fd.norm())) << c.name << " -df/dv";
      // Dissipative: the force does negative work on the velocity relative to the collider.
      EXPECT_LE(force(x, v, nullptr, nullptr).dot(v - P.velocity_at(x)), 0.0) << c.name;
    }
  }
}

TEST(MeshCollider, AFaceIsItsPlaneAndASphereItsClosedFormToTheSplinesError) {
  // A box's surface: more than two cells from its edges the spline reproduces the face's linear
  // distance exactly (a cubic B-spline reproduces linear functions).
  Points x;
  std::vector<Tri> tris;
  box_surface(Vec3(0.2, 0.1, 0.15), x, tris);
  const MeshSdf box(x, tris, 0.01, 0.02, "box");
  for (const double dz : {0.004, -0.01}) {
    Vec3 g;
    Mat3 H;
    EXPECT_NEAR(box.distance(Vec3(0.03, 0.01, 0.15 + dz), &g, &H), dz, 1e-12);
    EXPECT_LT((g - Vec3::UnitZ()).norm(), 1e-10);
    EXPECT_LT(H.norm(), 1e-7);
  }
  // The exact distance through the tree: beyond an edge, beyond a corner, inside.
  EXPECT_NEAR(box.exact_distance(Vec3(0.23, 0.0, 0.19)), std::hypot(0.03, 0.04), 1e-14);
  EXPECT_NEAR(box.exact_distance(Vec3(0.22, 0.12, -0.17)), std::sqrt(3) * 0.02, 1e-14);
  EXPECT_NEAR(box.exact_distance(Vec3(0.0, 0.09, 0.0)), -0.01, 1e-14);
  // A triangulated sphere: its triangles lie between the radii R - sag and R, so the exact
  // distance is |x| - R within sag; the spline adds (h^2 / 6) Laplacian(|x| - R) = h^2 / (3 |x|)
  // to first order, so what is left after that term is of higher order in h.
  const double R = 0.2;
  icosphere(R, 6, x, tris);
  double sag = 0;
  for (const Tri& T : tris) {
    const Vec3 a = x.col(T[0]), b = x.col(T[1]), c = x.col(T[2]);
    sag = std::max(sag, R - std::abs((b - a).cross(c - a).normalized().dot(a)));
  }
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1, 1);
  for (const double h : {0.02, 0.01}) {
    const MeshSdf sphere(x, tris, h, 0.03, "sphere");
    double worst_exact = 0, worst_first = 0, worst_rest = 0;
    for (int i = 0; i < 200; ++i) {
      const Vec3 p = Vec3(u(rng), u(rng), u(rng)).normalized() * (R + 0.02 * u(rng));
      const double closed = p.norm() - R, first = h * h / (3 * p.norm());
      worst_exact = std::max(worst_exact, std::abs(sphere.exact_distance(p) - closed));
      worst_first = std::max(worst_first, first);
      worst_rest = std::max(worst_rest, std::abs(sphere.distance(p, nullptr, nullptr) - closed - first));
    }
    EXPECT_LE(worst_exact, sag + 1e-15) << h;
    EXPECT_LT(worst_rest, sag + 0.1 * worst_first)
        << "cell " << h << ": the spline's error is not h^2 / (3 r) to first order";
  }
}

TEST(MeshCollider, ItsOrientationDoesNotMatterAndBadSurfacesAreNamed) {
  Points x;
  std::vector<Tri> tris;
  box_surface(Vec3(0.2, 0.1, 0.15), x, tris);
  const MeshSdf out(x, tris, 0.02, 0.02, "box");
  for (Tri& T : tris) std::swap(T[1], T[2]);  // every triangle turned inwards
  const MeshSdf in(x, tris, 0.02, 0.02, "box");
  for (const Vec3& p : {Vec3(0.0, 0.0, 0.0), Vec3(0.21, 0.0, 0.0), Vec3(0.1, 0.05, 0.149)})
    EXPECT_EQ(out.distance(p, nullptr, nullptr), in.distance(p, nullptr, nullptr));
  tris.pop_back();
  EXPECT_NE(test::error_of([&] {
              MeshSdf(x, tris, 0.02, 0.02, "holed.obj");
            }).find("holed.obj: the surface is not closed (3 edges"),
            std::string::npos);
  const std::string mesh =
      "[mesh]\nshape = \"box\"\nsize = [0.1, 0.1, 0.1]\ncells = 1\ncenter = [0, 0, 0.2]\n[material]\nmu = 1.0\nlambda "
      "= 1.0\n";
  auto err = [&](const std::string& collider) {
    return test::error_of(
        [&] { parse_scene(SceneFile::parse(mesh + "[[collider]]\nshape = \"mesh\"\n" + collider, "c.toml")); });
  };
  EXPECT_NE(err("").find("collider[0].file: missing"), std::string::npos);
  EXPECT_NE(err("file = \"" ISOCHOR_SOURCE_DIR "/tests/data/open_box.obj\"\n")
                .find("collider[0].file: " ISOCHOR_SOURCE_DIR "/tests/data/open_box.obj: the surface is not closed"),
            std::string::npos);
  EXPECT_NE(err("file = \"" ISOCHOR_SOURCE_DIR "/tests/data/good_box.toml\"\n")
                .find("collider[0].file: \"" ISOCHOR_SOURCE_DIR "/tests/data/good_box.toml\" has an unknown extension"),
            std::string::npos);
}

TEST(Colliders, RelativeVelocityIsTheRateOfTheDistance) {
  // The damping and friction see v - w(x), w the collider material's velocity at x: then
  // n . (v - w) is the time derivative of s along a node moving at v (the dg/dt-like term of a
  // moving collider), for a translating and a turning one.
  for (bool turning : {false, true})
    for (Collider c : shapes()) {
      c.motion = Driver{};
      if (turning) {
        c.motion.kind = Driver::Kind::keyframes_cubic;
        c.motion.rotation = true;
        c.motion.axis = Vec3(0.2, 1, 0.5).normalized();
        c.motion.center = Vec3(-0.1, 0.3, 0.2);
        c.motion.times = {0.0, 1.0};
        c.motion.values = {Vec3::Zero(), Vec3(1.2, 0, 0)};
      } else {
        c.motion.kind = Driver::Kind::sinusoid;
        c.motion.vector = Vec3(0.05, -0.02, 0.04);
        c.motion.frequency = 2.0;
      }
      const double t = 0.4, h = 1e-6;
      const ColliderPose P = c.pose(t, nullptr);
      const Vec3 v(0.3, -0.1, 0.2);
      for (const Vec3& x : near_surface(c, P, 0.02, 10, 11)) {
        Vec3 n;
        c.distance(P, x, &n, nullptr);
        const double sdot = n.dot(v - P.velocity_at(x));
        const double fd = (c.distance(c.pose(t + h, nullptr), x + h * v, nullptr, nullptr) -
                           c.distance(c.pose(t - h, nullptr), x - h * v, nullptr, nullptr)) /
                          (2 * h);
        EXPECT_NEAR(sdot, fd, 1e-6) << c.name << (turning ? " turning" : " translating");
      }
    }
}

TEST(Colliders, ACollidersBoneCarriesItAsItsBoundNodes) {
  // A box collider on a pin-jointed bone: a point fixed in the collider is where the skeleton puts
  // a mesh node bound to that bone at the same rest position, with the same velocity.
  const std::string text = R"(
[mesh]
shape = "box"
size = [1.0, 1.0, 1.0]
cells = 4
center = [0.5, 0.5, 0.5]
[material]
model = "cnh"
mu = 1000.0
lambda = 1000.0
[skeleton]
[[skeleton.bone]]
name = "arm"
joint = "pin"
origin = [0.5, 0.5, 0.5]
axis = [1.0, 2.0, 2.0]
motion = "sinusoid"
amplitude = [70.0]
frequency = 0.7
phase = 0.3
select = { kind = "box", min = [0.95, -0.1, -0.1], max = [1.1, 1.1, 1.1] }
[[collider]]
shape = "box"
center = [1.5, 0.5, 0.5]
size = [0.4, 0.3, 0.2]
axis = [0.0, 1.0, 1.0]
angle = 20.0
bone = "arm"
)";
  const Scene s = parse_scene(SceneFile::parse(text, "bone_collider.toml"));
  ASSERT_EQ(s.colliders.size(), 1u);
  const Collider& c = s.colliders[0];
  const Points& X = s.mesh.rest_positions();
  for (double t : {0.1, 0.45, 1.2}) {
    Points x = X;
    Eigen::VectorXd v = Eigen::VectorXd::Zero(3 * X.cols());
    s.drive(t, x, &v);
    const ColliderPose P = c.pose(t, s.skeleton.get());
    for (int n : s.skeleton->bones()[0].nodes) {
      const Vec3 l = c.rotation.transpose() * (X.col(n) - c.center);  // the node's rest point in the collider's frame
      EXPECT_LT((P.A * l + P.b - x.col(n)).norm(), 1e-12) << "t " << t;
      EXPECT_LT((P.velocity_at(x.col(n)) - v.segment<3>(3 * n)).norm(), 1e-12) << "t " << t;
    }
  }
}

TEST(Colliders, BadCollidersAreNamed) {
  const std::string mesh =
      "[mesh]\nshape = \"box\"\nsize = [0.1, 0.1, 0.1]\ncells = 1\ncenter = [0, 0, 0.2]\n[material]\nmu = 1.0\nlambda "
      "= 1.0\n";
  auto err = [&](const std::string& collider) {
    return test::error_of([&] { parse_scene(SceneFile::parse(mesh + "[[collider]]\n" + collider, "c.toml")); });
  };
  EXPECT_NE(err("radius = 0.1\n").find("collider[0].shape: missing"), std::string::npos);
  EXPECT_NE(err("shape = \"cone\"\n").find("collider[0].shape"), std::string::npos);
  EXPECT_NE(err("shape = \"sphere\"\n").find("collider[0].radius: missing"), std::string::npos);
  EXPECT_NE(err("shape = \"box\"\nsize = [0.1, 0.0, 0.1]\n").find("collider[0].size: expected three positive"),
            std::string::npos);
  EXPECT_NE(err("shape = \"cylinder\"\nradius = 0.1\nlength = 0.1\nrounding = 0.2\n")
                .find("collider[0].rounding: expected at most"),
            std::string::npos);
  EXPECT_NE(
      err("shape = \"sphere\"\nradius = 0.1\nbone = \"arm\"\n").find("collider[0].bone: the scene has no [skeleton]"),
      std::string::npos);
  EXPECT_NE(err("shape = \"sphere\"\nradius = 0.1\nsize = [1, 1, 1]\n").find("size"),
            std::string::npos);  // not a sphere's key
  // The body inside a sphere at t = 0: its 8 corners are 0.0866 m from the centre.
  EXPECT_NE(
      err("shape = \"sphere\"\nradius = 0.1\ncenter = [0, 0, 0.2]\n")
          .find("collider[0].shape: 8 of 8 nodes start more than the contact thickness (0.001 m) inside this sphere"),
      std::string::npos);
}

namespace {

// A stiff 0.1 m block (1 kg) resting on the top face (z = 0) of a box collider under gravity
// tilted by `tilt` degrees about y (a slope), with the given friction. It starts at the
// penetration p where its 9 bottom nodes carry its weight, 9 k p^2 = m g cos(tilt).
Scene block_on_box(double tilt, double friction, const std::string& kind, const std::string& mesh_file = "") {
  const double a = tilt * M_PI / 180.0, p = std::sqrt(9.81 * std::cos(a) / 9 / 1e8);
  char text[2048];
  std::snprintf(text, sizeof text, R"(
[mesh]
shape = "box"
size = [0.1, 0.1, 0.1]
cells = 2
center = [0.0, 0.0, %.17g]
[material]
model = "snh"
mu = 2e6
lambda = 2e6
[forces]
gravity = [%.17g, 0.0, %.17g]
[contact]
stiffness = 1e8
thickness = 1e-3
damping = 100.0
[[collider]]
%s
friction = %.17g
slip_speed = 1e-3
[integrator]
kind = "%s"
%s
)",
                0.05 + 1e-3 - p, 9.81 * std::sin(a), -9.81 * std::cos(a),
                (mesh_file.empty() ? std::string("shape = \"box\"\ncenter = [0.0, 0.0, -0.05]\nsize = [2.0, 2.0, 0.1]")
                                   : "shape = \"mesh\"\nfile = \"" + mesh_file + "\"")
                    .c_str(),
                friction, kind.c_str(),
                kind == "static"
                    ? "[frames]\ncount = 3"
                    : "rtol = 1e-6\natol = 1e-9\n[damping]\nbeta = 1e-3\n[frames]\nrate = 20\nduration = 0.3");
  return parse_scene(SceneFile::parse(text, "block.toml"));
}

}  // namespace

TEST(Colliders, ABlockRestsOnABoxWithItsWeight) {
  // Statics: the box collider carries the block's weight, m g = 9.81 N (written per node).
  const auto dir = test::temp_dir();
  const Scene sc = block_on_box(0.0, 0.0, "static");
  RunFile f(run_scene(sc, (dir / "rest.h5").string(), false).output);
  const Points F = f.contact(f.num_frames() - 1);
  EXPECT_NEAR(F.row(2).sum(), 1000.0 * 1e-3 * 9.81, 1e-6 * 9.81);
  EXPECT_NEAR(F.row(0).sum(), 0.0, 1e-9);
  int touching = 0;
  for (int i = 0; i < F.cols(); ++i) touching += F.col(i).norm() > 0;
  EXPECT_EQ(touching, 9);  // the bottom face's 3 x 3 nodes
}

TEST(MeshCollider, ABlockRestsOnATriangulatedBoxWithItsWeight) {
  // As ABlockRestsOnABoxWithItsWeight, the box given as 12 triangles: under the block, far from
  // the box's edges, the mesh's smoothed distance is the plane's, so the same m g.
  const auto dir = test::temp_dir();
  Points x;
  std::vector<Tri> tris;
  box_surface(Vec3(1.0, 1.0, 0.05), x, tris);
  const std::string file = (dir / "slab.obj").string();
  {
    std::ofstream obj(file);
    for (int i = 0; i < x.cols(); ++i) obj << "v " << x(0, i) << " " << x(1, i) << " " << x(2, i) - 0.05 << "\n";
    for (const Tri& T : tris) obj << "f " << T[0] + 1 << " " << T[1] + 1 << " " << T[2] + 1 << "\n";
  }
  RunFile f(run_scene(block_on_box(0.0, 0.0, "static", file), (dir / "rest.h5").string(), false).output);
  const Points F = f.contact(f.num_frames() - 1);
  EXPECT_NEAR(F.row(2).sum(), 1000.0 * 1e-3 * 9.81, 1e-6 * 9.81);
  int touching = 0;
  for (int i = 0; i < F.cols(); ++i) touching += F.col(i).norm() > 0;
  EXPECT_EQ(touching, 9);
}

TEST(Colliders, ABlockSlidesDownATiltedBoxAtCoulombsAcceleration) {
  // On a 30 degree slope with friction 0.3 < tan 30: a = g (sin 30 - 0.3 cos 30) = 2.3564 m/s^2;
  // with 0.8 > tan 30 it sticks, creeping at the slip speed's v = eps r / sqrt(1 - r^2),
  // r = tan 30 / 0.8, where the smoothed friction balances the weight's pull along the slope.
  const auto dir = test::temp_dir();
  const double a = 30 * M_PI / 180.0, g = 9.81;
  const Vec3 along = Vec3::UnitX();  // down the slope (gravity is tilted)
  auto slope_speed = [&](double friction, std::vector<double>& speed) {
    const Scene sc = block_on_box(30.0, friction, "ida");
    RunFile f(run_scene(sc, (dir / ("slide" + std::to_string(friction) + ".h5")).string(), false).output);
    speed.clear();
    for (int k = 0; k < f.num_frames(); ++k) {
      const Points v = f.velocities(k);
      speed.push_back(v.rowwise().mean().dot(along));
    }
    return f.times();
  };
  std::vector<double> v;
  const std::vector<double> t = slope_speed(0.3, v);
  ASSERT_EQ(t.size(), 7u);
  const double acc = (v[6] - v[2]) / (t[6] - t[2]);
  EXPECT_NEAR(acc, g * (std::sin(a) - 0.3 * std::cos(a)), 1e-3 * g);
  slope_speed(0.8, v);
  const double r = std::tan(a) / 0.8, creep = 1e-3 * r / std::sqrt(1 - r * r);
  EXPECT_NEAR(v[6], creep, 1e-3 * creep);
  EXPECT_NEAR(v[4], creep, 1e-3 * creep);
}

TEST(Colliders, ABandTightensByItsResizeFactors) {
  // A hollow cylinder (a band of hole radius 0.2 m) whose radius goes to 0.9 of it over 1 s
  // (linear keys): a point in its hole at distance r from the axis is 0.2 f(t) - r from it.
  const std::string mesh =
      "[mesh]\nshape = \"box\"\nsize = [0.1, 0.1, 0.1]\ncells = 1\n[material]\nmu = 1.0\nlambda = 1.0\n";
  const std::string band =
      "[[collider]]\nshape = \"cylinder\"\nradius = 0.2\nwall = 0.02\nlength = 0.05\n"
      "resize = { times = [0.0, 1.0], factors = [1.0, 0.9] }\n";
  const Scene s = parse_scene(SceneFile::parse(mesh + band, "band.toml"));
  ASSERT_EQ(s.colliders.size(), 1u);
  for (double t : {0.0, 0.25, 1.0, 2.0}) {
    const ColliderPose P = s.colliders[0].pose(t, nullptr);
    const double f = 1.0 - 0.1 * std::min(t, 1.0);
    EXPECT_NEAR(P.radius_scale, f, 1e-15);
    EXPECT_NEAR(s.colliders[0].distance(P, Vec3(0.03, 0.04, 0.01), nullptr, nullptr), 0.2 * f - 0.05, 1e-15);
  }
  const std::vector<double> b = s.breakpoints();
  EXPECT_NE(std::find(b.begin(), b.end(), 1.0), b.end());  // the knot: a stop for IDA
  auto err = [&](const std::string& extra) {
    return test::error_of([&] { parse_scene(SceneFile::parse(mesh + band + extra, "band.toml")); });
  };
  EXPECT_NE(err("damping = 0.1\n").find("collider[0].resize: a collider whose radius changes has no damping"),
            std::string::npos);
  EXPECT_NE(
      test::error_of([&] {
        parse_scene(SceneFile::parse(mesh + "[[collider]]\nshape = \"box\"\nsize = [1, 1, 1]\ncenter = [0, 0, 2]\n"
                                            "resize = { times = [0.0, 1.0], factors = [1.0, 0.9] }\n",
                                     "box.toml"));
      }).find("collider[0].resize: only a sphere's, capsule's or cylinder's radius can change"),
      std::string::npos);
}

TEST(Colliders, TheWaistbandHoldsTheWaistInsideItsTighteningBand) {
  // demos/waistband_dynamic.toml to t = 0.5 s, where the band's radius is 0.95 of 0.131 m (its
  // cubic keys at the middle): the waist (0.13 m at rest) stays inside the band, no surface node
  // under it farther from the axis than the band's radius plus the contact thickness, while every
  // zone (the whole body and 8 painted ones) keeps its volume.
  const auto dir = test::temp_dir();
  Scene sc = load_scene(std::string(ISOCHOR_SOURCE_DIR) + "/demos/waistband_dynamic.toml", {"frames.duration=0.5"});
  ASSERT_EQ(sc.zones.size(), 9u);
  RunFile f(run_scene(sc, (dir / "waist.h5").string(), false).output);
  ASSERT_EQ(f.num_frames(), 11);
  const auto volumes = f.volumes();
  for (std::size_t k = 0; k < volumes.size(); ++k)
    for (std::size_t z = 0; z < volumes[k].size(); ++z)
      EXPECT_NEAR(volumes[k][z] / volumes[0][z], 1.0, 1e-10) << "frame " << k;
  const Points X = f.positions(0), x = f.positions(f.num_frames() - 1);
  const double R = 0.131 * 0.95, delta = 2e-3;
  double widest_rest = 0, widest = 0;
  for (int v : sc.mesh.surface_nodes())
    if (std::abs(X(2, v) - 0.40) < 0.02) {
      widest_rest = std::max(widest_rest, std::hypot(X(0, v), X(1, v)));
      widest = std::max(widest, std::hypot(x(0, v), x(1, v)));
    }
  EXPECT_GT(widest_rest, R + delta);  // the band had to squeeze
  EXPECT_LE(widest, R + delta);
  const Points F = f.contact(f.num_frames() - 1);
  double inward = 0;  // the band pushes towards the axis
  for (int v = 0; v < F.cols(); ++v) inward -= F.col(v).head<2>().dot(x.col(v).head<2>().normalized());
  EXPECT_GT(inward, 0.0);
}

// One mesh of two boxes (b's nodes after a's), every node free, with the assembly whose pattern
// the contact's Hessian fills.
struct TwoBoxes {
  TwoBoxes(const Mesh& a, const Mesh& b)
      : m(join(a, b)), dofs(DofMap::make(m.num_nodes(), {})), assembly(m, make_snh(1, 1), dofs) {}
  static Mesh join(const Mesh& a, const Mesh& b) {
    Points X(3, a.num_nodes() + b.num_nodes());
    X << a.rest_positions(), b.rest_positions();
    std::vector<Tet> tets = a.tets();
    for (Tet t : b.tets()) {
      for (int& v : t) v += a.num_nodes();
      tets.push_back(t);
    }
    return Mesh(X, tets);
  }
  Mesh m;
  DofMap dofs;
  ElasticAssembly assembly;
};

TEST(SelfContact, GradientAgainstFiniteDifferencesAndTheNodesOwnBlock) {
  // One mesh of a 0.1 m box and a 0.02 m box 0.2 m above it at rest, the small one then moved
  // down to 3 mm above the large one's top face (within the 6 mm contact thickness), every node
  // moved at random by up to 0.5 mm: the small box's four bottom nodes touch the top face's
  // triangles. The energy's gradient against central differences (nodes and triangle corners);
  // a touching node, whose closest point is inside a face, has the exact 3x3 block 2 k p n n^T on
  // itself (the corners' blocks are Gauss-Newton: the pattern keeps only these blocks,
  // docs/decisions.md).
  const Mesh a = make_box(Eigen::Vector3d(0.1, 0.1, 0.1), {1, 1, 1}, Eigen::Vector3d(0, 0, 0), 6);
  const Mesh b = make_box(Eigen::Vector3d(0.02, 0.02, 0.02), {1, 1, 1}, Eigen::Vector3d(0.004, -0.007, 0.2), 6);
  const TwoBoxes boxes(a, b);
  const Mesh& m = boxes.m;
  const Points& X = m.rest_positions();
  const DofMap& dofs = boxes.dofs;
  const ElasticAssembly& asm_ = boxes.assembly;
  ContactLaw law{1e5, 0.006};
  SelfContact self(m, law, 0.05, dofs, asm_.pattern());
  Points x = X;
  x.rightCols(b.num_nodes()).row(2).array() -= 0.2 - 0.053 - 0.01;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-5e-4, 5e-4);
  for (int i = 0; i < x.size(); ++i) x.data()[i] += u(rng);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(x.size());
  const double E = self.add_gradient(x, g);
  ASSERT_GT(E, 0.0);
  const double h = 1e-7;
  double worst = 0;
  for (int i = 0; i < x.size(); ++i) {
    Points xp = x, xm = x;
    xp.data()[i] += h;
    xm.data()[i] -= h;
    Eigen::VectorXd unused = Eigen::VectorXd::Zero(x.size());
    const double fd = (self.add_gradient(xp, unused) - self.add_gradient(xm, unused)) / (2 * h);
    worst = std::max(worst, std::abs(fd - g[i]));
  }
  EXPECT_LT(worst, 1e-6 * g.cwiseAbs().maxCoeff());
  // A bottom node of the small box.
  const int centre = a.num_nodes();
  ASSERT_LT(x(2, centre), 0.05 + 0.006);
  std::vector<double> values(asm_.pattern().nnz(), 0.0);
  self.add_hessian(x, 1.0, values.data());
  Mat3 H, Hfd;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) H(r, c) = values[asm_.pattern().find(3 * centre + r, 3 * centre + c)];
  for (int c = 0; c < 3; ++c) {
    Points xp = x, xm = x;
    xp(c, centre) += h;
    xm(c, centre) -= h;
    Eigen::VectorXd gp = Eigen::VectorXd::Zero(x.size()), gm = Eigen::VectorXd::Zero(x.size());
    self.add_gradient(xp, gp);
    self.add_gradient(xm, gm);
    Hfd.col(c) = (gp - gm).segment<3>(3 * centre) / (2 * h);
  }
  EXPECT_GT(H.norm(), 0.0);
  EXPECT_LT((H - Hfd).norm(), 1e-5 * Hfd.norm());
  // Normal damping: dissipative, and the touching node's own block of -df/dv against central
  // differences (the force is linear in the velocities).
  ContactLaw damped = law;
  damped.damping = 0.5;
  SelfContact dself(m, damped, 0.05, dofs, asm_.pattern());
  Eigen::VectorXd v(x.size());
  for (int i = 0; i < v.size(); ++i) v[i] = u(rng) * 1000;
  Eigen::VectorXd gd = Eigen::VectorXd::Zero(x.size());
  dself.add_damping(x, v, gd);
  EXPECT_GT(gd.dot(v), 0.0);  // -f . v > 0: it dissipates
  std::vector<double> D(asm_.pattern().nnz(), 0.0);
  dself.add_damping_jacobian(x, D.data());
  Mat3 Dn, Dfd;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) Dn(r, c) = D[asm_.pattern().find(3 * centre + r, 3 * centre + c)];
  for (int c = 0; c < 3; ++c) {
    Eigen::VectorXd vp = v, vm = v, gp = Eigen::VectorXd::Zero(x.size()), gm = Eigen::VectorXd::Zero(x.size());
    vp[3 * centre + c] += 1e-3;
    vm[3 * centre + c] -= 1e-3;
    dself.add_damping(x, vp, gp);
    dself.add_damping(x, vm, gm);
    Dfd.col(c) = (gp - gm).segment<3>(3 * centre) / 2e-3;
  }
  EXPECT_GT(Dn.norm(), 0.0);
  EXPECT_LT((Dn - Dfd).norm(), 1e-8 * Dfd.norm());
}

namespace {
// How far the upper block's bottom nodes (rest z = z_bottom, index >= first) are below the lower
// block's deformed top face (its surface triangles at rest z = z_top, indices < first), measured
// along z under each node (m; negative: above it).
double deepest_below(const Mesh& m, const Points& x, int first, double z_top, double z_bottom) {
  const Points& X = m.rest_positions();
  double deepest = -std::numeric_limits<double>::infinity();
  for (const Tri& t : m.surface()) {
    bool top = true;
    for (int v : t) top = top && v < first && std::abs(X(2, v) - z_top) < 1e-12;
    if (!top) continue;
    for (int p = first; p < m.num_nodes(); ++p) {
      if (std::abs(X(2, p) - z_bottom) > 1e-12) continue;
      const Vec3 a(x(0, t[0]), x(1, t[0]), 0), b(x(0, t[1]), x(1, t[1]), 0), c(x(0, t[2]), x(1, t[2]), 0);
      const Vec3 w = barycentric(Vec3(x(0, p), x(1, p), 0), a, b, c);
      if (w.minCoeff() < 0) continue;  // not above this triangle
      deepest = std::max(deepest, w[0] * x(2, t[0]) + w[1] * x(2, t[1]) + w[2] * x(2, t[2]) - x(2, p));
    }
  }
  return deepest;
}
}  // namespace

// The candidate pairs are found once and kept while no surface node has moved more than half
// their skin (a Verlet list): along a walk of a small box sinking into a large one, in steps of
// up to 0.4 or 2.4 mm against a 6 mm thickness (so the candidates are kept for some steps and found
// again at others), the contact energy and gradient of the one object that keeps its candidates
// equal, bit for bit, those of a new object that searches at each configuration afresh. The small
// box also slides 6 cm across the top face, over triangles that were far at the first search.
TEST(SelfContact, KeptCandidatesGiveWhatAFreshSearchGives) {
  const Mesh a = make_box(Eigen::Vector3d(0.1, 0.1, 0.1), {3, 3, 3}, Eigen::Vector3d(0, 0, 0), 6);
  const Mesh b = make_box(Eigen::Vector3d(0.03, 0.03, 0.03), {2, 2, 2}, Eigen::Vector3d(0.004, -0.007, 0.2), 6);
  const TwoBoxes boxes(a, b);
  const Mesh& m = boxes.m;
  const Points& X = m.rest_positions();
  const DofMap& dofs = boxes.dofs;
  const ElasticAssembly& asm_ = boxes.assembly;
  const ContactLaw law{1e5, 0.006};
  const SelfContact kept(m, law, 0.02, dofs, asm_.pattern());
  Points x = X;
  x.rightCols(b.num_nodes()).row(2).array() -= 0.2 - 0.058 - 0.015;  // 8 mm above the top face
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  int touching = 0;
  for (int step = 0; step < 40; ++step) {
    const double size = step % 5 == 4 ? 2.4e-3 : 4e-4;
    x.rightCols(b.num_nodes()).row(2).array() -= 0.25 * size;               // sinks 8 mm in all,
    x.rightCols(b.num_nodes()).row(0).array() += 1.5e-3;                    // slides 6 cm over the top face,
    for (int i = 0; i < x.size(); ++i) x.data()[i] += 0.5 * size * u(rng);  // every node jiggled
    Eigen::VectorXd g1 = Eigen::VectorXd::Zero(x.size()), g2 = Eigen::VectorXd::Zero(x.size());
    const SelfContact fresh(m, law, 0.02, dofs, asm_.pattern());
    const double E1 = kept.add_gradient(x, g1), E2 = fresh.add_gradient(x, g2);
    ASSERT_EQ(E1, E2) << "step " << step;
    ASSERT_EQ((g1 - g2).cwiseAbs().maxCoeff(), 0.0) << "step " << step;
    touching += E1 > 0;
  }
  EXPECT_GT(touching, 10);  // the walk reached contact and stayed in it
}

TEST(SelfContact, TwoBlocksPressedTogetherDoNotPassThrough) {
  // One mesh of two 4 cm blocks 2 cm apart (a TetGen file): the lower one's base held, the upper
  // one's top driven down by 3.5 cm over 0.5 s. Without contact between parts the upper block
  // passes about 1.5 cm into the lower one; with it, no bottom node of the upper block goes below
  // the lower block's top face by more than the contact thickness.
  const auto dir = test::temp_dir();
  const Mesh a = make_box(Eigen::Vector3d(0.04, 0.04, 0.04), {2, 2, 2}, Eigen::Vector3d(0, 0, 0.02), 6);
  std::ostringstream node, ele;
  node << 2 * a.num_nodes() << " 3 0 0\n";
  for (int k = 0; k < 2; ++k)
    for (int i = 0; i < a.num_nodes(); ++i) {
      const Eigen::Vector3d p = a.rest_positions().col(i) + Eigen::Vector3d(0.003 * k, 0.002 * k, 0.06 * k);
      node << k * a.num_nodes() + i << " " << p.x() << " " << p.y() << " " << p.z() << "\n";
    }
  ele << 2 * a.num_tets() << " 4 0\n";
  for (int k = 0; k < 2; ++k)
    for (int e = 0; e < a.num_tets(); ++e) {
      ele << k * a.num_tets() + e;
      for (int v : a.tets()[e]) ele << " " << v + k * a.num_nodes();
      ele << "\n";
    }
  test::write_file(dir / "blocks.node", node.str());
  test::write_file(dir / "blocks.ele", ele.str());
  const std::string scene = R"(
[mesh]
file = "blocks.node"
[material]
model = "snh"
mu = 2000.0
lambda = 8000.0
[forces]
gravity = [0.0, 0.0, 0.0]
[damping]
beta = 2e-3
[[boundary]]
select = { kind = "box", min = [-1.0, -1.0, -0.001], max = [1.0, 1.0, 0.001] }
[[boundary]]
select = { kind = "box", min = [-1.0, -1.0, 0.099], max = [1.0, 1.0, 0.101] }
kind = "keyframes"
times = [0.0, 0.5]
values = [0.0, 0.0, 0.0, 0.0, 0.0, -0.035]
interpolation = "cubic"
[contact.self]
law = "area"
stiffness = 1e11
thickness = 2e-3
exclude = 0.015
[integrator]
rtol = 1e-4
atol = 1e-7
[frames]
rate = 10.0
duration = 0.5
)";
  for (bool on : {false, true}) {
    const Scene sc = parse_scene(SceneFile::parse(
        scene, "blocks.toml", {on ? "contact.self.enabled=true" : "contact.self.enabled=false"}, dir.string()));
    RunFile f(run_scene(sc, (dir / (on ? "on.h5" : "off.h5")).string(), false).output);
    ASSERT_EQ(f.num_frames(), 6);
    const double deepest = deepest_below(sc.mesh, f.positions(5), sc.mesh.num_nodes() / 2, 0.04, 0.06);
    if (on) {
      EXPECT_LE(deepest, 2e-3);
    } else {
      EXPECT_GT(deepest, 0.01);  // the check sees a block passing into the other
    }
    std::printf("contact between parts %s: deepest penetration %.2f mm\n", on ? "on" : "off", 1000 * deepest);
  }
}
