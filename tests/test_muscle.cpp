// The muscle term (muscle.hpp): Blemker's force-length relation against its published values and
// its own integral; the fibre energy's derivatives in I4, the tet term's gradient, Hessian and
// H d against central differences on stretched, compressed and inverted tets; the assembly with
// fibres against finite differences and its lean gradient path against the general one.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <functional>
#include <random>

#include "isochor/base/error.hpp"
#include "isochor/core/meshing.hpp"
#include "isochor/models/assembly.hpp"
#include "isochor/models/muscle.hpp"
#include "scene_runs.hpp"
#include "test_util.hpp"

using namespace isochor;

namespace {

MuscleLaw law(double k1 = 4.0e3, double k2 = 2.0, double L = 1.1) {
  MuscleLaw m;
  m.sigma_max = 3.0e4;
  m.optimal_stretch = L;
  m.k1 = k1;
  m.k2 = k2;
  return m;
}

Vec12 random_tet(std::mt19937& rng, double squash) {
  std::uniform_real_distribution<double> u(-0.15, 0.15);
  Vec12 x;
  x << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  for (int i = 0; i < 12; ++i) x[i] += u(rng);
  for (int a = 0; a < 4; ++a) x[3 * a] *= squash;  // stretch (> 1), compress, or invert (< 0) along x
  return x;
}

}  // namespace

TEST(Muscle, ForceLengthIsBlemkersCurve) {
  // Blemker et al. 2005, eq. (10): the peak 1 at the optimal length, 0.36 where the pieces meet,
  // zero outside [0.4, 1.6]; continuous at 0.6 and 1.4.
  EXPECT_DOUBLE_EQ(force_length(1.0).f, 1.0);
  EXPECT_NEAR(force_length(0.6).f, 0.36, 1e-15);
  EXPECT_NEAR(force_length(0.6 + 1e-12).f, 0.36, 1e-10);
  EXPECT_NEAR(force_length(1.4).f, 0.36, 1e-15);
  EXPECT_NEAR(force_length(1.4 - 1e-12).f, 0.36, 1e-10);
  EXPECT_EQ(force_length(0.3).f, 0.0);
  EXPECT_EQ(force_length(1.7).f, 0.0);
  EXPECT_EQ(force_length(1.0).integral, 0.0);
  // The integral is the antiderivative of f and f' the derivative, everywhere but at the knots.
  const double h = 1e-6;
  for (double u = 0.35; u < 1.7; u += 0.0371) {
    EXPECT_NEAR((force_length(u + h).integral - force_length(u - h).integral) / (2 * h), force_length(u).f, 1e-8) << u;
    EXPECT_NEAR((force_length(u + h).f - force_length(u - h).f) / (2 * h), force_length(u).df, 1e-7) << u;
  }
  // The whole area under the curve: 2 * 0.024 + the middle piece's 0.8 - 8/3 * 0.064.
  EXPECT_NEAR(force_length(2.0).integral - force_length(0.0).integral, 0.048 + 0.8 - 8.0 / 3.0 * 0.064, 1e-14);
}

TEST(Muscle, FibreEnergyDerivativesInI4) {
  const MuscleLaw m = law();
  for (double a : {0.0, 0.3, 1.0})
    for (double I4 = 0.2; I4 < 2.9; I4 += 0.0973) {
      const double h = 1e-6;
      const FibreEnergy e = fibre_energy(m, a, I4), p = fibre_energy(m, a, I4 + h), q = fibre_energy(m, a, I4 - h);
      EXPECT_NEAR(e.d1, (p.psi - q.psi) / (2 * h), 1e-5 * (1 + std::abs(e.d1))) << a << " " << I4;
      EXPECT_NEAR(e.d2, (p.d1 - q.d1) / (2 * h), 1e-5 * (1 + std::abs(e.d2))) << a << " " << I4;
    }
  // At rest: no energy, and the along-fibre stress is the active peak scaled by f_L(1 / lambda_ofl).
  const FibreEnergy rest = fibre_energy(m, 0.5, 1.0);
  EXPECT_EQ(rest.psi, 0.0);
  EXPECT_NEAR(fibre_stress(m, 0.5, 1.0), 0.5 * m.sigma_max * force_length(1.0 / 1.1).f, 1e-9);
  // Passive alone, tension only: zero in compression, HGO's 2 lambda k1 d exp(k2 d^2) in tension.
  EXPECT_EQ(fibre_stress(m, 0.0, 0.9), 0.0);
  const double d = 1.2 * 1.2 - 1.0;
  EXPECT_NEAR(fibre_stress(m, 0.0, 1.2), 2.0 * 1.2 * m.k1 * d * std::exp(m.k2 * d * d), 1e-9);
}

TEST(Muscle, TetTermMatchesCentralDifferences) {
  std::mt19937 rng(3);
  const Vec3 a0 = Vec3(1.0, 0.4, -0.3).normalized();
  for (const MuscleLaw& m : {law(), law(4.0e3, 0.0, 0.9), law(0.0, 0.0, 1.0)})
    for (double squash : {1.25, 0.7, -0.8}) {
      const Vec12 X = random_tet(rng, 1.0), x = random_tet(rng, squash);
      const TetShape s = TetShape::make(X.segment<3>(0), X.segment<3>(3), X.segment<3>(6), X.segment<3>(9));
      Vec12 g, Hd, d = Vec12::Random();
      Mat12 H;
      const double E = fibre_tet_energy(m, 0.8, a0, s, x, &g, &H, &d, &Hd);
      const double h = 1e-6;
      Vec12 gfd;
      Mat12 Hfd;
      for (int i = 0; i < 12; ++i) {
        Vec12 xp = x, xm = x, gp, gm;
        xp[i] += h;
        xm[i] -= h;
        gfd[i] =
            (fibre_tet_energy(m, 0.8, a0, s, xp, &gp, nullptr) - fibre_tet_energy(m, 0.8, a0, s, xm, &gm, nullptr)) /
            (2 * h);
        Hfd.col(i) = (gp - gm) / (2 * h);
      }
      EXPECT_NE(E, 0.0);
      EXPECT_LT((g - gfd).norm(), 1e-6 * (1 + g.norm())) << "squash " << squash;
      EXPECT_LT((H - Hfd).norm(), 1e-6 * (1 + H.norm())) << "squash " << squash;
      EXPECT_LT((Hd - H * d).norm(), 1e-12 * (1 + Hd.norm()));
      // Without the Hessian, H d is the same.
      Vec12 Hd2;
      fibre_tet_energy(m, 0.8, a0, s, x, nullptr, nullptr, &d, &Hd2);
      EXPECT_LT((Hd2 - Hd).norm(), 1e-12 * (1 + Hd.norm()));
      // Rigid translation costs nothing: every row of H sums to zero over the nodes per axis.
      for (int k = 0; k < 3; ++k) {
        Vec12 t = Vec12::Zero();
        for (int a = 0; a < 4; ++a) t[3 * a + k] = 1.0;
        EXPECT_LT((H * t).norm(), 1e-9 * (1 + H.norm()));
      }
    }
}

TEST(Muscle, AssemblyWithFibresMatchesFiniteDifferences) {
  const Mesh mesh = make_box(Eigen::Vector3d(1, 0.8, 0.6), {3, 2, 2}, Eigen::Vector3d::Zero(), 5);
  const DofMap dofs = DofMap::make(mesh.num_nodes(), mesh.node_sets.at("zmin"));
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-0.08, 0.08);
  Points x = mesh.rest_positions();
  for (int i = 0; i < x.size(); ++i) x.data()[i] += u(rng);
  x.row(0) *= 1.2;
  ElasticAssembly a(mesh, make_cnh(2.0e3, 3.0e4, 1.0, 0.1), dofs);
  FibreField field;
  field.muscles = {law(), law(0.0, 0.0, 1.0)};
  for (int e = 0; e < mesh.num_tets(); ++e) {
    field.muscle_of.push_back(e % 3 == 0 ? -1 : e % 2);  // two muscles and plain tets
    field.direction.push_back(Vec3(1.0, 0.1 * (e % 5), -0.2).normalized());
  }
  a.set_fibres(field);
  a.set_activations({0.7, 0.4});
  EXPECT_THROW(a.set_activations({0.1}), Error);
  ElasticAssembly plain(mesh, make_cnh(2.0e3, 3.0e4, 1.0, 0.1), dofs);
  EXPECT_GT(std::abs(a.energy(x) - plain.energy(x)), 1.0);  // the fibres add energy
  Eigen::VectorXd lean;
  a.gradient(x, lean);
  const double h = 1e-6;
  for (int i = 0; i < x.size(); i += 5) {
    Points xp = x, xm = x;
    xp.data()[i] += h;
    xm.data()[i] -= h;
    EXPECT_NEAR(lean[i], (a.energy(xp) - a.energy(xm)) / (2 * h), 1e-6 * (1 + std::abs(lean[i])));
  }
  // The general path's gradient and Hessian.
  Eigen::VectorXd general = Eigen::VectorXd::Zero(x.size());
  std::vector<double> values(a.pattern().nnz(), 0.0);
  ElementPass p;
  p.grad = &general;
  p.values = values.data();
  a.evaluate(x, p);
  EXPECT_LT((lean - general).norm(), 1e-13 * general.norm());
  const int nf = dofs.num_free();
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(3 * nf, 3 * nf), Hfd(3 * nf, 3 * nf);
  const Pattern& pat = a.pattern();
  for (Index c = 0; c < pat.n; ++c)
    for (Index k = pat.col_ptr[c]; k < pat.col_ptr[c + 1]; ++k) H(pat.row_ind[k], c) += values[k];
  for (int f = 0; f < nf; ++f)
    for (int d = 0; d < 3; ++d) {
      Points xp = x, xm = x;
      xp(d, dofs.free_nodes[f]) += h;
      xm(d, dofs.free_nodes[f]) -= h;
      Eigen::VectorXd gp, gm;
      a.gradient(xp, gp);
      a.gradient(xm, gm);
      for (int g = 0; g < nf; ++g)
        Hfd.block<3, 1>(3 * g, 3 * f + d) = (gp - gm).segment<3>(3 * dofs.free_nodes[g]) / (2 * h);
    }
  EXPECT_LT((H - Hfd).norm() / Hfd.norm(), 1e-6);
  // Removing the muscles gives back the plain body.
  a.set_fibres(FibreField{});
  EXPECT_DOUBLE_EQ(a.energy(x), plain.energy(x));
}

// ---- Bundles in a scene: the one-dimensional answers of a homogeneous fibre-aligned bar ----

namespace {

Scene bundle_scene(const std::string& extra, const std::vector<std::string>& overrides = {}) {
  const std::string text = std::string(test::kRollerBar) + R"(
[[muscle]]
name = "bundle"
select = { kind = "all" }
direction = [1.0, 0.0, 0.0]
sigma_max = 2000.0
optimal_stretch = 1.05
passive_k1 = 300.0
passive_k2 = 0.5
)" + extra;
  return parse_scene(SceneFile::parse(text, "bundle.toml", overrides));
}

// Runs a scene and calls f(t, system, lambda) at every frame, the system set to the frame's state.
template <class F>
void each_frame(const Scene& sc, F&& f) {
  test::run_frames(sc, [&](double t, SceneSystem& sys, const VectorXd&, const VectorXd& lambda) { f(t, sys, lambda); });
}

constexpr double kMu = 1000.0, kSigma = 2000.0, kOptimal = 1.05, kK1 = 300.0, kK2 = 0.5, kArea = 0.25;

// The bar's nominal stress along x at stretch l, written out from the papers' formulas: the
// incompressible neo-Hookean mu (l - l^-2), Blemker's active sigma_max a f_L(l / l_ofl), and the
// HGO passive fibre 2 l k1 (l^2 - 1) exp(k2 (l^2 - 1)^2) in tension.
double bar_stress(double l, double a) {
  const double u = l / kOptimal;
  double fL = 0;
  if (u >= 0.4 && u <= 0.6) fL = 9 * (u - 0.4) * (u - 0.4);
  if (u > 0.6 && u < 1.4) fL = 1 - 4 * (1 - u) * (1 - u);
  if (u >= 1.4 && u <= 1.6) fL = 9 * (u - 1.6) * (u - 1.6);
  const double d = l * l - 1;
  const double passive = d > 0 ? 2 * l * kK1 * d * std::exp(kK2 * d * d) : 0.0;
  return kMu * (l - 1 / (l * l)) + kSigma * a * fL + passive;
}

// The free bar's stretch at activation a: the root of bar_stress in (0.45, 1] by bisection.
double free_stretch(double a) {
  double lo = 0.45 * kOptimal, hi = 1.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (bar_stress(mid, a) > 0 ? hi : lo) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace

// A free bar of muscle (rollers on three symmetry planes, nothing on its end) activated from 0 to
// a = 0.8 over the increments shortens to the stretch where the matrix, active and passive
// stresses balance (bisection of the 1-D law), thickens by lambda^-1/2 sideways, and keeps its
// volume exactly.
TEST(MuscleBundle, FreeBundleShortensToItsOneDimensionalEquilibrium) {
  const Scene sc = bundle_scene("activation_keys = { times = [0.0, 1.0], values = [0.0, 0.8] }\n");
  const std::vector<int>& end = sc.mesh.node_sets.at("xmax");
  const std::vector<int>& side = sc.mesh.node_sets.at("ymax");
  double worst_stretch = 0, worst_lateral = 0, worst_volume = 0, last = 1;
  each_frame(sc, [&](double t, SceneSystem& sys, const VectorXd&) {
    const double expected = free_stretch(0.8 * t);
    for (int n : end) worst_stretch = std::max(worst_stretch, std::abs(sys.positions()(0, n) - expected));
    for (int n : side)
      worst_lateral = std::max(worst_lateral, std::abs(sys.positions()(1, n) - 0.5 / std::sqrt(expected)));
    const std::vector<double> v = sys.volumes();
    worst_volume = std::max(worst_volume, std::abs(v[0] - 0.25) / 0.25);
    last = expected;
  });
  std::printf("a = 0.8: stretch %.6f; positions within %.2e (end) and %.2e (side) m; volume within %.1e\n", last,
              worst_stretch, worst_lateral, worst_volume);
  EXPECT_LT(last, 0.9);  // it does shorten, by more than a tenth
  EXPECT_LT(worst_stretch, 1e-8);
  EXPECT_LT(worst_lateral, 1e-8);
  EXPECT_LT(worst_volume, 1e-9);  // statics stops at a scaled residual of 1e-9 (statics.hpp: residual_tol)
}

// An isometric bar (both ends held along x) stretched to l with activation a: the end face's
// reaction is the whole nominal stress times the rest area, active part sigma_max a f_L included.
TEST(MuscleBundle, IsometricEndForceIsSigmaMaxTimesActivationTimesForceLength) {
  for (double stretch : {0.9, 1.0, 1.25}) {
    const Scene sc = bundle_scene(
        "activation = 0.6\n[[boundary]]\nselect = { kind = \"set\", name = \"xmax\" }\n"
        "components = [\"x\"]\nkind = \"ramp\"\nt1 = 1.0\ndisplacement = [" +
        std::to_string(stretch - 1.0) + ", 0.0, 0.0]\n");
    const int count = static_cast<int>(sc.mesh.node_sets.at("xmax").size());
    double pull = 0;
    each_frame(sc, [&](double t, SceneSystem&, const VectorXd& lambda) {
      if (t == 1.0) pull = -lambda.tail(count).sum();  // the end face's rows come last
    });
    const double expected = bar_stress(stretch, 0.6) * kArea;
    std::printf("stretch %.2f: end force %.9f N, formula %.9f N\n", stretch, pull, expected);
    EXPECT_NEAR(pull, expected, 1e-8 * std::abs(expected));
  }
}

// With activation_scale = 0 the same bar stays as it was (passive), and the activation written
// with every frame is the keyframes' (linear in the increments) times the scale.
TEST(MuscleBundle, ActivationScaleZeroLeavesTheBarPassive) {
  const Scene sc =
      bundle_scene("activation_keys = { times = [0.0, 1.0], values = [0.0, 0.8] }\n", {"muscles.activation_scale=0"});
  double moved = 0;
  each_frame(sc, [&](double, SceneSystem& sys, const VectorXd&) {
    moved = std::max(moved, (sys.positions() - sc.mesh.rest_positions()).cwiseAbs().maxCoeff());
  });
  EXPECT_LT(moved, 1e-12);
  const Scene half =
      bundle_scene("activation_keys = { times = [0.0, 1.0], values = [0.0, 0.8] }\n", {"muscles.activation_scale=0.5"});
  EXPECT_DOUBLE_EQ(half.activations(0.5)[0], 0.5 * 0.4);
}

// A knee whose Xrotation turns 24 degrees per frame to 240 degrees over 10 frames of 0.1 s, written
// as a mocap file writes angles, wrapped into (-180, 180] (192 is -168): with the table
// a(0) = 0, a(240) = 1 the activation is the angle over 240 at each frame and, the cubic through
// linear keys being that line between interior keys, at any time from the second frame to the
// second last; held after the clip. Without the unwrapping the last four frames would read 0.
TEST(MuscleBundle, ActivationFollowsABvhChannelThroughItsTable) {
  std::string bvh =
      "HIERARCHY\nROOT Hip\n{\n  OFFSET 0 0 0\n  CHANNELS 3 Zrotation Xrotation Yrotation\n  JOINT Knee\n  {\n"
      "    OFFSET 0 -0.4 0\n    CHANNELS 3 Zrotation Xrotation Yrotation\n    End Site\n    {\n      OFFSET 0 -0.4 0\n"
      "    }\n  }\n}\nMOTION\nFrames: 11\nFrame Time: 0.1\n";
  for (int f = 0; f <= 10; ++f) {
    const double angle = 24.0 * f;
    bvh += "0 0 0 5 " + std::to_string(angle > 180 ? angle - 360 : angle) + " 0\n";
  }
  const std::string path = test::write_file(test::temp_dir() / "knee.bvh", bvh);
  const auto with = [&](const std::string& channel, const std::vector<std::string>& overrides = {}) {
    return bundle_scene("activation_bvh = { file = \"" + path + "\", joint = \"Knee\", channel = \"" + channel +
                            "\", channel_values = [0.0, 240.0], values = [0.0, 1.0] }\n",
                        overrides);
  };
  const Scene sc = with("Xrotation");
  for (int f = 0; f <= 10; ++f) EXPECT_NEAR(sc.activations(0.1 * f)[0], 0.1 * f, 1e-12) << "frame " << f;
  for (double t : {0.15, 0.45, 0.83}) EXPECT_NEAR(sc.activations(t)[0], t, 1e-12) << "t = " << t;
  EXPECT_NEAR(sc.activations(3.0)[0], 1.0, 1e-12);
  const std::vector<double> breaks = sc.breakpoints();
  EXPECT_NE(std::find(breaks.begin(), breaks.end(), 1.0), breaks.end());  // the clip's last key
  EXPECT_NEAR(with("Xrotation", {"muscles.activation_scale=0.5"}).activations(0.5)[0], 0.25, 1e-12);
  EXPECT_NEAR(with("Zrotation").activations(0.5)[0], 5.0 / 240, 1e-12);  // the Hip's 5 degrees, not the Knee's

  const auto message = [&](const std::string& extra) { return test::error_of([&] { bundle_scene(extra); }); };
  EXPECT_NE(
      message("activation_bvh = { file = \"" + path +
              "\", joint = \"Knee\", channel = \"Xposition\", channel_values = [0.0, 1.0], values = [0.0, 1.0] }\n")
          .find("muscle[0].activation_bvh.channel: joint \"Knee\" of " + path +
                " has no channel \"Xposition\" (its channels: Zrotation, Xrotation, Yrotation)"),
      std::string::npos);
  EXPECT_NE(
      message("activation_bvh = { file = \"" + path +
              "\", joint = \"Ankle\", channel = \"Xrotation\", channel_values = [0.0, 1.0], values = [0.0, 1.0] }\n")
          .find("muscle[0].activation_bvh.joint: \"Ankle\" is not a joint of " + path),
      std::string::npos);
  EXPECT_NE(message("activation_bvh = { file = \"no_such.bvh\", joint = \"Knee\", channel = \"Xrotation\", "
                    "channel_values = [0.0, 1.0], values = [0.0, 1.0] }\n")
                .find("muscle[0].activation_bvh.file: no_such.bvh: "),
            std::string::npos)
      << message(
             "activation_bvh = { file = \"no_such.bvh\", joint = \"Knee\", channel = \"Xrotation\", "
             "channel_values = [0.0, 1.0], values = [0.0, 1.0] }\n");
  EXPECT_NE(message("activation_bvh = { file = \"" + path + "\", channel_values = [0.0, 1.0], values = [0.0, 1.0] }\n")
                .find("muscle[0].activation_bvh.joint: missing"),
            std::string::npos);
  EXPECT_NE(
      message("activation_keys = { times = [0.0, 1.0], values = [0.0, 1.0] }\nactivation_bvh = { file = \"" + path +
              "\", joint = \"Knee\", channel = \"Xrotation\", channel_values = [0.0, 1.0], values = [0.0, "
              "1.0] }\n")
          .find("expected one of activation_keys, activation_joint or activation_bvh"),
      std::string::npos);
}

namespace {
// A fibre that differs from tet to tet: a function of the tet's centroid.
Vec3 fibre_at(const Vec3& c) { return Vec3(1 + c.y(), c.z() - 0.3, 0.5 + c.x()); }

Vec3 centroid(const Mesh& m, int e) {
  Vec3 c = Vec3::Zero();
  for (int k = 0; k < 4; ++k) c += m.rest_positions().col(m.tets()[e][k]) / 4;
  return c;
}

// `box` as a Gmsh 2.2 .msh file whose element tags run backwards (1000 + 3 (n - 1 - e)), with
// element data "fibres" (fibre_at of each tet's centroid; `skip` gets none) and "weight" (one
// number per tet).
std::string msh_with_element_data(const Mesh& box, const std::string& name, int skip = -1) {
  std::string t = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n" + std::to_string(box.num_nodes()) + "\n";
  char line[256];
  for (int n = 0; n < box.num_nodes(); ++n) {
    const Vec3 x = box.rest_positions().col(n);
    std::snprintf(line, sizeof line, "%d %.17g %.17g %.17g\n", n + 1, x.x(), x.y(), x.z());
    t += line;
  }
  const int m = box.num_tets();
  const auto tag = [m](int e) { return 1000 + 3 * (m - 1 - e); };
  t += "$EndNodes\n$Elements\n" + std::to_string(m) + "\n";
  for (int e = 0; e < m; ++e) {
    const Tet& k = box.tets()[e];
    std::snprintf(line, sizeof line, "%d 4 2 1 1 %d %d %d %d\n", tag(e), k[0] + 1, k[1] + 1, k[2] + 1, k[3] + 1);
    t += line;
  }
  t += "$EndElements\n$ElementData\n1\n\"fibres\"\n1\n0.0\n3\n0\n3\n" + std::to_string(m - (skip >= 0)) + "\n";
  for (int e = 0; e < m; ++e) {
    if (e == skip) continue;
    const Vec3 a = fibre_at(centroid(box, e));
    std::snprintf(line, sizeof line, "%d %.17g %.17g %.17g\n", tag(e), a.x(), a.y(), a.z());
    t += line;
  }
  t += "$EndElementData\n$ElementData\n1\n\"weight\"\n1\n0.0\n3\n0\n1\n" + std::to_string(m) + "\n";
  for (int e = 0; e < m; ++e) t += std::to_string(tag(e)) + " 0.5\n";
  t += "$EndElementData\n";
  return test::write_file(test::temp_dir() / name, t);
}

Scene scene_on_mesh(const std::string& mesh, const std::string& muscle) {
  return parse_scene(SceneFile::parse("[mesh]\n" + mesh + R"(
[material]
model = "cnh"
mu = 1000.0
lambda = 5000.0
[forces]
gravity = [0.0, 0.0, 0.0]
[integrator]
kind = "static"
[frames]
count = 2
[[muscle]]
name = "bundle"
select = { kind = "all" }
)" + muscle,
                                      "on_mesh.toml"));
}
}  // namespace

// Fibres read per tet from the scene's .msh file (Gmsh element data): each tet gets the vector the
// file gives its element tag, normalised, whatever order the tags run in; a field the file lacks,
// one of another size, a tet without a value and a mesh that is not a .msh file stop with one line.
TEST(MuscleBundle, FibresFromTheMeshFilesElementData) {
  const Mesh box = make_box(Vec3(1.0, 0.5, 0.5), {3, 2, 2}, Vec3(0.5, 0.25, 0.25), 6);
  const std::string path = msh_with_element_data(box, "bar.msh");
  const Scene sc = scene_on_mesh("file = \"" + path + "\"\n", "fibres = \"mesh\"\n");
  ASSERT_EQ(sc.mesh.num_tets(), box.num_tets());
  const Scene::MuscleSpec& m = sc.muscles.at(0);
  ASSERT_EQ(m.tets.size(), static_cast<std::size_t>(box.num_tets()));
  double worst = 0;
  for (std::size_t k = 0; k < m.tets.size(); ++k)
    worst = std::max(worst, (m.fibres[k] - fibre_at(centroid(sc.mesh, m.tets[k])).normalized()).norm());
  EXPECT_LT(worst, 1e-14);

  const auto message = [&](const std::string& mesh, const std::string& muscle) {
    return test::error_of([&] { scene_on_mesh(mesh, muscle); });
  };
  const std::string file = "file = \"" + path + "\"\n";
  EXPECT_NE(message(file, "fibres = \"mesh\"\nfield = \"fibers\"\n")
                .find("muscle[0].field: the mesh has no element data \"fibers\" (it has: fibres, weight)"),
            std::string::npos)
      << message(file, "fibres = \"mesh\"\nfield = \"fibers\"\n");
  EXPECT_NE(message(file, "fibres = \"mesh\"\nfield = \"weight\"\n")
                .find("element data \"weight\" has 1 components per tet, expected 3"),
            std::string::npos);
  const std::string holed = "file = \"" + msh_with_element_data(box, "holed.msh", 7) + "\"\n";
  EXPECT_NE(message(holed, "fibres = \"mesh\"\n").find("element data \"fibres\" gives tet "), std::string::npos)
      << message(holed, "fibres = \"mesh\"\n");
  EXPECT_NE(message(holed, "fibres = \"mesh\"\n").find(" of the muscle no value"), std::string::npos);
  EXPECT_NE(message("shape = \"box\"\n", "fibres = \"mesh\"\n").find("muscle[0].field: the mesh has no element data"),
            std::string::npos);
}

// ---- The Laplace fibre field ----

namespace {
// A box's nodes x in [1, 2], y in [0, 1] mapped to a quarter annulus: radius x, angle y pi / 2.
Mesh quarter_annulus(long cells) {
  const Mesh box = make_box(Eigen::Vector3d(1, 1, 0.2), {cells, 2 * cells, 1}, Eigen::Vector3d(1.5, 0.5, 0.1), 5);
  Points X = box.rest_positions();
  for (int n = 0; n < X.cols(); ++n) {
    const double r = X(0, n), th = X(1, n) * M_PI / 2;
    X(0, n) = r * std::cos(th);
    X(1, n) = r * std::sin(th);
  }
  return Mesh(X, box.tets());
}

std::vector<int> all_tets(const Mesh& m) {
  std::vector<int> t(m.num_tets());
  for (int e = 0; e < m.num_tets(); ++e) t[e] = e;
  return t;
}

std::vector<int> nodes_where(const Mesh& m, const std::function<bool(const Vec3&)>& f) {
  std::vector<int> out;
  for (int n = 0; n < m.num_nodes(); ++n)
    if (f(m.rest_positions().col(n))) out.push_back(n);
  return out;
}
}  // namespace

// Between two opposite faces of a box, u = x / L is harmonic and linear, so the P1 solution is
// exact: every fibre is the x axis.
TEST(LaplaceFibres, BoxFromFaceToFaceIsTheAxis) {
  const Mesh box = make_box(Eigen::Vector3d(2, 0.5, 0.4), {6, 2, 2}, Eigen::Vector3d::Zero(), 5);
  const auto fibres = laplace_fibres(box, all_tets(box), box.node_sets.at("xmin"), box.node_sets.at("xmax"));
  double worst = 0;
  for (const Vec3& a : fibres) worst = std::max(worst, (a - Vec3::UnitX()).norm());
  EXPECT_LT(worst, 1e-12);
  // From insertion to origin the other way round.
  const auto back = laplace_fibres(box, all_tets(box), box.node_sets.at("xmax"), box.node_sets.at("xmin"));
  EXPECT_LT((back.front() + Vec3::UnitX()).norm(), 1e-12);
  EXPECT_THROW(laplace_fibres(box, all_tets(box), {}, box.node_sets.at("xmax")), Error);
}

// On a quarter annulus from the edge at angle 0 to the edge at pi / 2, the harmonic u is the angle
// over pi / 2 and its gradient the circumferential direction: the fibres are unit vectors that go
// round from origin to insertion, and their mean angle from e_theta falls about as h (P1 gradients
// converge at first order) when the mesh is refined twice.
TEST(LaplaceFibres, QuarterAnnulusRunsRoundFromOriginToInsertion) {
  double previous = 0;
  for (long cells : {2L, 4L}) {
    const Mesh m = quarter_annulus(cells);
    const auto origin = nodes_where(m, [](const Vec3& x) { return std::abs(x.y()) < 1e-9; });
    const auto insertion = nodes_where(m, [](const Vec3& x) { return std::abs(x.x()) < 1e-9; });
    const auto fibres = laplace_fibres(m, all_tets(m), origin, insertion);
    double mean_angle = 0, worst_unit = 0;
    for (int e = 0; e < m.num_tets(); ++e) {
      Vec3 c = Vec3::Zero();
      for (int k = 0; k < 4; ++k) c += m.rest_positions().col(m.tets()[e][k]) / 4;
      const Vec3 e_theta = Vec3(-c.y(), c.x(), 0).normalized();
      worst_unit = std::max(worst_unit, std::abs(fibres[e].norm() - 1));
      mean_angle += std::acos(std::min(1.0, fibres[e].dot(e_theta))) / m.num_tets();
    }
    std::printf("%ld cells across: mean angle from e_theta %.4f rad\n", cells, mean_angle);
    EXPECT_LT(worst_unit, 1e-12);
    EXPECT_LT(mean_angle, 0.25);  // every fibre goes round, none across
    if (previous > 0) {
      EXPECT_LT(mean_angle, previous / 1.6);
    }
    previous = mean_angle;
  }
}

// Bad [[muscle]] keys stop with one line naming the key.
TEST(MuscleBundle, BadKeysNameTheKey) {
  const auto message = [](const std::string& extra, const std::vector<std::string>& overrides = {}) {
    try {
      bundle_scene(extra, overrides);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("activation = 1.5\n").find("muscle[0].activation: expected a number in [0, 1]"), std::string::npos)
      << message("activation = 1.5\n");
  EXPECT_NE(message("zone = \"nowhere\"\n").find("muscle[0].zone: expected exactly one of zone"), std::string::npos);
  EXPECT_NE(message("fibres = \"file\"\nfile = \"no_such_fibres.csv\"\n").find("muscle[0].file: "), std::string::npos)
      << message("fibres = \"file\"\nfile = \"no_such_fibres.csv\"\n");
  EXPECT_NE(message("[[muscle]]\nname = \"bundle\"\nselect = { kind = \"all\" }\ndirection = [1.0, 0.0, 0.0]\n")
                .find("muscle[1].name: muscle \"bundle\" is defined twice"),
            std::string::npos);
  EXPECT_NE(message("[[muscle]]\nname = \"other\"\nselect = { kind = \"all\" }\ndirection = [1.0, 0.0, 0.0]\n")
                .find("is also in muscle \"bundle\""),
            std::string::npos);
  EXPECT_NE(message("activation_joint = { bone = \"forearm\", angles = [0.0, 90.0], values = [0.0, 1.0] }\n")
                .find("muscle[0].activation_joint.bone: the scene has no [skeleton]"),
            std::string::npos);
  EXPECT_NE(message("activation_keys = { times = [0.0, 1.0], values = [0.0, 2.0] }\n")
                .find("activation_keys.values: expected activations in [0, 1]"),
            std::string::npos);
  EXPECT_NE(message("fibres = \"laplace\"\n").find("muscle[0].origin: missing"), std::string::npos);
}

// ---- Material regions ----

// Two layers side by side along y (y < 0.25 at mu = 1 kPa, y > 0.25 at mu = 3 kPa and twice the
// density), stretched along x by their end face: each layer is in uniaxial tension at the same
// stretch with the same lateral contraction lambda^-1/2, so the end force is the layers' sum,
// (mu_1 + mu_2) / 2 A (lambda - lambda^-2), and the mass is each layer's density times its volume.
// The layers hold different pressures (each its own sigma_yy = 0), so each is its own zone: one
// zone over both would give them one pressure, and the penalty would make up the difference by
// letting J leave 1.
TEST(MaterialRegions, LayersInParallelCarryTheSumOfTheirStresses) {
  const double stretch = 1.5;
  const Scene sc = parse_scene(SceneFile::parse(std::string(test::kRollerBar) + R"(
[[zones.zone]]
name = "soft"
select = { kind = "box", min = [-1.0, -1.0, -1.0], max = [2.0, 0.25, 1.0] }
[[zones.zone]]
name = "stiff"
select = { kind = "box", min = [-1.0, 0.25, -1.0], max = [2.0, 1.0, 1.0] }
[[material.region]]
select = { kind = "box", min = [-1.0, 0.25, -1.0], max = [2.0, 1.0, 1.0] }
mu = 3000.0
density = 2000.0
[[boundary]]
select = { kind = "set", name = "xmax" }
components = ["x"]
kind = "ramp"
t1 = 1.0
displacement = [0.5, 0.0, 0.0]
)",
                                                "layers.toml", {"zones.global=false"}));
  ASSERT_EQ(sc.material.regions.size(), 1u);
  EXPECT_EQ(sc.material.regions[0].lambda, 5000.0);  // the body's, not given
  const int count = static_cast<int>(sc.mesh.node_sets.at("xmax").size());
  double pull = 0, mass = 0;
  test::run_frames(sc, [&](double t, SceneSystem& sys, const VectorXd&, const VectorXd& lambda) {
    if (t == 1.0) pull = -lambda.tail(count).sum();
    mass = sys.mass().sum() / 3.0;
  });
  const double expected = (1000.0 + 3000.0) / 2 * 0.25 * (stretch - 1 / (stretch * stretch));
  std::printf("end force %.9f N, formula %.9f N\n", pull, expected);
  EXPECT_NEAR(pull, expected, 1e-8 * expected);
  // Every node here is free (rollers only): the lumped masses sum to the body's mass.
  EXPECT_NEAR(mass, 1000.0 * 0.125 + 2000.0 * 0.125, 1e-9);
}

// The assembly with a material per tet: its energy is the sum of each tet's energy under its own
// material, and its gradient the energy's central differences.
TEST(MaterialRegions, AssemblyTakesEachTetsMaterial) {
  const Mesh mesh = make_box(Eigen::Vector3d(1, 0.8, 0.6), {3, 2, 2}, Eigen::Vector3d::Zero(), 5);
  const DofMap dofs = DofMap::make(mesh.num_nodes(), mesh.node_sets.at("zmin"));
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.1, 0.1);
  Points x = mesh.rest_positions();
  for (int i = 0; i < x.size(); ++i) x.data()[i] += u(rng);
  const std::vector<std::shared_ptr<const Material>> m = {make_cnh(1.0, 5.0, 1.0, 0.1), make_cnh(4.0, 20.0, 1.0, 0.1)};
  std::vector<int> of(mesh.num_tets());
  double expected = 0;
  for (int e = 0; e < mesh.num_tets(); ++e) {
    of[e] = e % 2;
    const Tet& t = mesh.tets()[e];
    const Points& X = mesh.rest_positions();
    expected += tet_energy(*m[of[e]], TetShape::make(X.col(t[0]), X.col(t[1]), X.col(t[2]), X.col(t[3])), gather(x, t),
                           nullptr, nullptr);
  }
  ElasticAssembly a(mesh, m[0], dofs);
  a.set_tet_materials(m, of);
  EXPECT_NEAR(a.energy(x), expected, 1e-12 * expected);
  Eigen::VectorXd g;
  a.gradient(x, g);
  const double h = 1e-6;
  for (int i = 0; i < x.size(); i += 5) {
    Points xp = x, xm = x;
    xp.data()[i] += h;
    xm.data()[i] -= h;
    EXPECT_NEAR(g[i], (a.energy(xp) - a.energy(xm)) / (2 * h), 1e-6 * (1 + std::abs(g[i])));
  }
  EXPECT_THROW(a.set_tet_materials(m, std::vector<int>(mesh.num_tets(), 2)), Error);
}
