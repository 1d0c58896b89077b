// The muscle term (muscle.hpp): Blemker's force-length relation against its published values and
// its own integral; the fibre energy's derivatives in I4, the tet term's gradient, Hessian and
// H d against central differences on stretched, compressed and inverted tets; the assembly with
// fibres against finite differences and its lean gradient path against the general one.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

#include "isochor/base/error.hpp"
#include "isochor/core/meshing.hpp"
#include "isochor/models/assembly.hpp"
#include "isochor/models/muscle.hpp"

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
      const TetShape s =
          TetShape::make(X.segment<3>(0), X.segment<3>(3), X.segment<3>(6), X.segment<3>(9));
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
        gfd[i] = (fibre_tet_energy(m, 0.8, a0, s, xp, &gp, nullptr) - fibre_tet_energy(m, 0.8, a0, s, xm, &gm, nullptr)) /
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
