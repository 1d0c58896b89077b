// Element kernels against central differences, on random deformed and inverted elements.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <functional>
#include <random>

#include "isochor/models/elements.hpp"

using namespace isochor;

namespace {

template <int N>
using V = Eigen::Matrix<double, N, 1>;
template <int N>
using M = Eigen::Matrix<double, N, N>;

// Central differences of f (value) and g (gradient) at x.
template <int N>
void check_derivatives(const std::function<double(const V<N>&, V<N>*, M<N>*)>& f, const V<N>& x, const char* what,
                       double tol = 1e-6) {
  V<N> g;
  M<N> H;
  f(x, &g, &H);
  V<N> gfd;
  M<N> Hfd;
  const double h = 1e-6 * std::max(1.0, x.norm() / std::sqrt(N));
  for (int k = 0; k < N; ++k) {
    V<N> xp = x, xm = x;
    xp[k] += h;
    xm[k] -= h;
    gfd[k] = (f(xp, nullptr, nullptr) - f(xm, nullptr, nullptr)) / (2 * h);
    V<N> gp, gm;
    f(xp, &gp, nullptr);
    f(xm, &gm, nullptr);
    Hfd.col(k) = (gp - gm) / (2 * h);
  }
  EXPECT_LT((g - gfd).norm() / std::max(1e-12, gfd.norm()), tol) << what << " at " << x.transpose();
  EXPECT_LT((H - Hfd).norm() / std::max(1e-12, Hfd.norm()), tol) << what;
  EXPECT_LT((H - H.transpose()).norm(), 1e-10 * (1 + H.norm())) << what;
}

Vec12 rest_tet() {
  Vec12 X;
  X << 0.1, 0, 0, 1, 0.2, 0, 0, 1.1, 0.1, 0.2, 0.1, 0.9;
  return X;
}

}  // namespace

TEST(Elements, TetEnergyOfEveryMaterial) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  const Vec12 X = rest_tet();
  const TetShape s = TetShape::make(X.segment<3>(0), X.segment<3>(3), X.segment<3>(6), X.segment<3>(9));
  std::vector<std::pair<const char*, std::unique_ptr<Material>>> mats;
  mats.emplace_back("unh", make_unh(2.0, 9.0));
  mats.emplace_back("snh", make_snh(2.0, 9.0));
  mats.emplace_back("cnh", make_cnh(2.0, 9.0, 1.0, 0.1));
  mats.emplace_back("xpbd_pair", make_xpbd_pair(2.0, 9.0));
  for (auto& [name, m] : mats)
    for (int trial = 0; trial < 10; ++trial) {
      Vec12 x = X;
      for (int i = 0; i < 12; ++i) x[i] += u(rng);
      // Odd trials invert the tet (swap two nodes' positions) where the material allows it.
      if (trial % 2 && m->invertible()) std::swap_ranges(x.data() + 6, x.data() + 9, x.data() + 9);
      check_derivatives<12>([&](const Vec12& y, Vec12* g, Mat12* H) { return tet_energy(*m, s, y, g, H); }, x, name);
    }
  // The element Hessian, built term by term, equals the pull-back of the material's 9x9 dP/dF.
  for (auto& [name, m] : mats)
    for (int trial = 0; trial < 5; ++trial) {
      Vec12 x = X;
      for (int i = 0; i < 12; ++i) x[i] += u(rng);
      Mat12 H;
      tet_energy(*m, s, x, nullptr, &H);
      const Mat12 ref = s.rest_volume * s.pull_back(m->dPdF(s.F(x)));
      EXPECT_LT((H - ref).norm(), 1e-12 * ref.norm()) << name;
    }
  // Zero force at rest and rigid-motion invariance of the energy.
  auto cnh = make_cnh(2.0, 9.0, 1.0, 0.1);
  Vec12 g;
  tet_energy(*cnh, s, X, &g, nullptr);
  EXPECT_LT(g.norm(), 1e-13);
}

TEST(Elements, TetVolume) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  for (int trial = 0; trial < 10; ++trial) {
    Vec12 x = rest_tet();
    for (int i = 0; i < 12; ++i) x[i] += u(rng);
    check_derivatives<12>([](const Vec12& y, Vec12* g, Mat12* H) { return tet_volume(y, g, H); }, x, "volume");
  }
  Vec12 x = rest_tet();
  const TetShape s = TetShape::make(x.segment<3>(0), x.segment<3>(3), x.segment<3>(6), x.segment<3>(9));
  EXPECT_NEAR(tet_volume(x, nullptr, nullptr), s.rest_volume, 1e-15);
}

TEST(Elements, TriangleAreaAndEpidermis) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  Vec9n X;
  X << 0, 0, 0, 1, 0, 0.1, 0.2, 0.9, 0;
  const double A0 = triangle_area(X, nullptr, nullptr);
  EXPECT_NEAR(A0, 0.5 * Vec3(1, 0, 0.1).cross(Vec3(0.2, 0.9, 0)).norm(), 1e-15);
  for (int trial = 0; trial < 10; ++trial) {
    Vec9n x = X;
    for (int i = 0; i < 9; ++i) x[i] += u(rng);
    check_derivatives<9>([](const Vec9n& y, Vec9n* g, Mat9n* H) { return triangle_area(y, g, H); }, x, "area");
    check_derivatives<9>([&](const Vec9n& y, Vec9n* g, Mat9n* H) { return epidermis_energy(A0, 3.0, 1.0, y, g, H); }, x,
                         "epidermis");
  }
  Vec9n g;
  EXPECT_EQ(epidermis_energy(A0, 3.0, 1.0, X, &g, nullptr), 0.0);
  EXPECT_LT(g.norm(), 1e-15);
}

TEST(Elements, SpringAndDamping) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  for (int trial = 0; trial < 10; ++trial) {
    Vec6 x, v;
    for (int i = 0; i < 6; ++i) {
      x[i] = u(rng) + (i >= 3 ? 1.0 : 0.0);
      v[i] = u(rng);
    }
    check_derivatives<6>([](const Vec6& y, Vec6* g, Mat6* H) { return spring_energy(3.0, 0.8, y, g, H); }, x, "spring");
    // Damping: derivatives of the force by positions and by velocities.
    Mat6 dfdx, dfdv, fdx, fdv;
    spring_damping_force(0.7, x, v, &dfdx, &dfdv);
    const double h = 1e-6;
    for (int k = 0; k < 6; ++k) {
      Vec6 xp = x, xm = x, vp = v, vm = v;
      xp[k] += h;
      xm[k] -= h;
      vp[k] += h;
      vm[k] -= h;
      fdx.col(k) =
          (spring_damping_force(0.7, xp, v, nullptr, nullptr) - spring_damping_force(0.7, xm, v, nullptr, nullptr)) /
          (2 * h);
      fdv.col(k) =
          (spring_damping_force(0.7, x, vp, nullptr, nullptr) - spring_damping_force(0.7, x, vm, nullptr, nullptr)) /
          (2 * h);
    }
    EXPECT_LT((dfdx - fdx).norm() / fdx.norm(), 1e-6);
    EXPECT_LT((dfdv - fdv).norm() / fdv.norm(), 1e-6);
    // Damping dissipates: f . v <= 0.
    EXPECT_LE(spring_damping_force(0.7, x, v, nullptr, nullptr).dot(v), 1e-15);
  }
}

TEST(Elements, GroundContactIsC2) {
  const Vec3 p(0, 0, 0.1), n(0, 0, 1);
  for (double z : {-0.05, 0.0, 0.09, 0.104, 0.2}) {
    Vec3 x(0.3, -0.2, z);
    using V3 = Eigen::Matrix<double, 3, 1>;
    check_derivatives<3>([&](const V3& y, V3* g, Mat3* H) { return ground_energy(50.0, 0.005, p, n, y, g, H); }, x,
                         "ground", z > 0.105 ? 1.0 : 1e-6);
  }
  // Continuity of energy, force and stiffness at the contact thickness.
  Vec3 g;
  Mat3 H;
  EXPECT_NEAR(ground_energy(50.0, 0.005, p, n, Vec3(0, 0, 0.105), &g, &H), 0.0, 1e-30);
  EXPECT_NEAR(ground_energy(50.0, 0.005, p, n, Vec3(0, 0, 0.105 - 1e-7), &g, &H), 0.0, 1e-19);
  EXPECT_LT(g.norm(), 1e-11);
  EXPECT_LT(H.norm(), 1e-4);
}

// H d computed without forming H equals the Hessian times d.
TEST(Elements, HessianTimesDirectionWithoutTheHessian) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  const TetShape s = TetShape::make(Vec3(0, 0, 0), Vec3(1, 0.1, 0), Vec3(0.2, 1, 0), Vec3(0.1, 0.3, 1.2));
  Vec12 x, d;
  for (int i = 0; i < 12; ++i) {
    x[i] = (i % 3 == 0 ? 1.1 : 1.0) * std::array<double, 12>{0, 0, 0, 1, 0.1, 0, 0.2, 1, 0, 0.1, 0.3, 1.2}[i] +
           0.05 * u(rng);
    d[i] = u(rng);
  }
  for (const auto& m : {make_unh(3, 20), make_snh(3, 20), make_cnh(3, 20, 2, 0.1), make_xpbd_pair(3, 20)}) {
    Mat12 H;
    Vec12 Hd;
    tet_energy(*m, s, x, nullptr, &H, nullptr, nullptr);
    tet_energy(*m, s, x, nullptr, nullptr, &d, &Hd);
    EXPECT_LT((H * d - Hd).norm(), 1e-12 * (H * d).norm()) << m->name();
  }
}
