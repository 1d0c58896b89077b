// Every material: gradient (P) and Hessian (dP/dF) against central differences on random deformed
// and inverted F; zero stress at rest; invariance under rotation; the closed forms of U and alpha~.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

#include "isochor/models/material.hpp"

using namespace isochor;

namespace {

Mat3 random_F(std::mt19937& rng, bool inverted) {
  std::uniform_real_distribution<double> u(-0.4, 0.4);
  Mat3 F = Mat3::Identity();
  for (int i = 0; i < 9; ++i) F(i % 3, i / 3) += u(rng);
  if (inverted) F.col(0) *= -1.0;
  return F;
}

Mat3 random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> n;
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  return q.normalized().toRotationMatrix();
}

double rel_err(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).norm() / std::max(1e-300, b.norm());
}

struct Case {
  const char* name;
  std::unique_ptr<Material> m;
  bool inverts;
};

std::vector<Case> all_materials() {
  std::vector<Case> c;
  c.push_back({"unh", make_unh(1.3, 7.0), false});
  c.push_back({"snh", make_snh(1.3, 7.0), true});
  c.push_back({"cnh", make_cnh(1.3, 7.0, 1.0, 0.1), true});
  c.push_back({"cnh_beta9", make_cnh(1.3, 7.0, 9.0, 0.3), true});
  c.push_back({"xpbd_pair", make_xpbd_pair(1.3, 7.0), true});
  return c;
}

}  // namespace

TEST(Materials, StressAndTangentMatchCentralDifferences) {
  std::mt19937 rng(7);
  for (auto& c : all_materials()) {
    for (int trial = 0; trial < 20; ++trial) {
      const bool inverted = c.inverts && trial % 2 == 1;
      const Mat3 F = random_F(rng, inverted);
      const double h = 1e-6;
      Mat3 Pfd;
      Mat9 Dfd;
      for (int k = 0; k < 9; ++k) {
        Mat3 Fp = F, Fm = F;
        Fp(k % 3, k / 3) += h;
        Fm(k % 3, k / 3) -= h;
        Pfd(k % 3, k / 3) = (c.m->psi(Fp) - c.m->psi(Fm)) / (2 * h);
        Mat3 dP = (c.m->P(Fp) - c.m->P(Fm)) / (2 * h);
        Dfd.col(k) = Eigen::Map<const Vec9>(dP.data());
      }
      EXPECT_LT(rel_err(c.m->P(F), Pfd), 1e-6) << c.name << " J = " << F.determinant();
      EXPECT_LT(rel_err(c.m->dPdF(F), Dfd), 1e-6) << c.name << " J = " << F.determinant();
      EXPECT_LT(rel_err(c.m->dPdF(F), c.m->dPdF(F).transpose()), 1e-12) << c.name;
    }
  }
}

TEST(Materials, DirectionalTangentMatchesCentralDifferencesOfTheStress) {
  // dP/dF : dF without dP/dF (evaluate_directional) against the central difference of P along dF,
  // and its psi and P against evaluate().
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (auto& c : all_materials()) {
    for (int trial = 0; trial < 20; ++trial) {
      const Mat3 F = random_F(rng, c.inverts && trial % 2 == 1);
      Mat3 dF;
      for (int k = 0; k < 9; ++k) dF(k % 3, k / 3) = u(rng);
      const double h = 1e-6;
      const Mat3 fd = (c.m->P(F + h * dF) - c.m->P(F - h * dF)) / (2 * h);
      Mat3 P, dP;
      const double psi = c.m->evaluate_directional(F, dF, &P, dP);
      EXPECT_LT(rel_err(dP, fd), 1e-6) << c.name << " J = " << F.determinant();
      EXPECT_EQ(psi, c.m->psi(F)) << c.name;
      EXPECT_LT(rel_err(P, c.m->P(F)), 1e-15) << c.name;
    }
  }
}

TEST(Materials, ZeroEnergyAndStressAtRest) {
  for (auto& c : all_materials()) {
    EXPECT_NEAR(c.m->psi(Mat3::Identity()), 0.0, 1e-14) << c.name;
    EXPECT_LT(c.m->P(Mat3::Identity()).norm(), 1e-13) << c.name;
  }
}

TEST(Materials, InvariantUnderRotation) {
  std::mt19937 rng(3);
  for (auto& c : all_materials()) {
    for (int trial = 0; trial < 5; ++trial) {
      const Mat3 F = random_F(rng, false), R = random_rotation(rng);
      EXPECT_NEAR(c.m->psi(R * F), c.m->psi(F), 1e-12 * (1 + std::abs(c.m->psi(F)))) << c.name;
      // P is objective: P(RF) = R P(F).
      EXPECT_LT(rel_err(c.m->P(R * F), R * c.m->P(F)), 1e-12) << c.name;
    }
  }
}

TEST(Materials, LinearisationMatchesLinearElasticityAtRest) {
  // Near rest every model should act as linear elasticity with the Lamé parameters given:
  // dP/dF at I applied to a small symmetric strain e gives 2 mu e + lambda tr(e) I.
  // (CNH: mu from the F-bar term, lambda from the penalty, since U''(1) = 1.)
  const double mu = 1.3, lambda = 7.0;
  Mat3 e;
  e << 0.3, 0.1, -0.2, 0.1, -0.5, 0.05, -0.2, 0.05, 0.4;
  const Mat3 expected = 2 * mu * e + lambda * e.trace() * Mat3::Identity();
  for (auto& c : all_materials()) {
    const Vec9 dP = c.m->dPdF(Mat3::Identity()) * Eigen::Map<const Vec9>(e.data());
    const Mat3 got = Eigen::Map<const Mat3>(dP.data());
    // UNH, SNH (through its re-parametrisation) and the XPBD pair (through lambda' = lambda + mu)
    // match exactly. CNH's F-bar term is purely deviatoric, 2 mu dev(e), and its penalty adds
    // lambda U''(1) tr(e) I with U''(1) = 1: so 2 mu e + (lambda - 2 mu / 3) tr(e) I.
    const bool cnh = std::string(c.name).rfind("cnh", 0) == 0;
    const Mat3 want = cnh ? Mat3(expected - 2.0 / 3.0 * mu * e.trace() * Mat3::Identity()) : expected;
    EXPECT_LT(rel_err(got, want), 1e-12) << c.name;
  }
}

TEST(Materials, SnhInIncompressibleUniaxialTensionIsStifferThanNeoHooke) {
  // At J = 1 a stretch l along x with l^-1/2 across is incompressible uniaxial stress once a
  // pressure cancels the lateral stress: the nominal stress is (sigma_xx - sigma_yy) / l. SNH's
  // isochoric part mu'/2 (I - 3) - mu'/2 log(I + 1), I = l^2 + 2 / l, gives
  // dW/dl = mu' I / (I + 1) (l - l^-2) with mu' = 4/3 mu: neo-Hooke's mu (l - l^-2) times
  // (4/3) I / (I + 1), 1 at rest and 10/9 at l = 2 (the note isochor run prints for snh).
  const double mu = 1.3;
  const auto snh = make_snh(mu, 7.0), unh = make_unh(mu, 7.0);
  for (double l : {1.2, 1.5, 2.0}) {
    const Mat3 F = Eigen::Vector3d(l, 1 / std::sqrt(l), 1 / std::sqrt(l)).asDiagonal();
    const auto nominal = [&](const Material& m) {
      const Mat3 sigma = m.P(F) * F.transpose();  // J = 1
      return (sigma(0, 0) - sigma(1, 1)) / l;
    };
    const double I = l * l + 2 / l;
    EXPECT_NEAR(nominal(*unh), mu * (l - 1 / (l * l)), 1e-12);
    EXPECT_NEAR(nominal(*snh) / nominal(*unh), 4.0 / 3.0 * I / (I + 1), 1e-12) << l;
  }
}

TEST(Penalty, ClosedFormsOfTheCnhPaper) {
  for (double beta : {0.0, 1.0, 9.0})
    for (double J : {-0.5, 0.0, 0.3, 1.0, 1.7}) {
      const Penalty u = penalty_U(J, beta);
      const double d = J - 1;
      EXPECT_NEAR(u.U, d * d * (beta * d * d + 6) / 12, 1e-15);  // (13)
      EXPECT_NEAR(u.dU, d * (beta * d * d + 3) / 3, 1e-15);      // (14)
      EXPECT_NEAR(u.d2U, beta * d * d + 1, 1e-15);               // (15)
      const double h = 1e-5;                                     // and they are derivatives of each other
      EXPECT_NEAR((penalty_U(J + h, beta).U - penalty_U(J - h, beta).U) / (2 * h), u.dU, 1e-8);
      EXPECT_NEAR((penalty_U(J + h, beta).dU - penalty_U(J - h, beta).dU) / (2 * h), u.d2U, 1e-8);
      if (beta == 0.0) {
        EXPECT_NEAR(u.U, 0.5 * d * d, 1e-15);  // U(J; 0) = (J - 1)^2 / 2
      }
    }
}

TEST(Penalty, AlphaTildeIsC2AtEpsilon) {
  const double eps = 0.1, h = 1e-9;
  const AlphaTilde above = alpha_tilde(eps + h, eps), below = alpha_tilde(eps - h, eps);
  EXPECT_NEAR(above.a, std::pow(eps, -1.0 / 3.0), 1e-7);
  EXPECT_NEAR(above.a, below.a, 1e-7);
  EXPECT_NEAR(above.da, below.da, 1e-5);
  EXPECT_NEAR(above.d2a, below.d2a, 1e-3 * above.d2a);
  for (double J : {-0.3, 0.05, 0.5, 2.0}) {
    const double d = 1e-6;
    EXPECT_NEAR((alpha_tilde(J + d, eps).a - alpha_tilde(J - d, eps).a) / (2 * d), alpha_tilde(J, eps).da, 1e-6);
    EXPECT_NEAR((alpha_tilde(J + d, eps).da - alpha_tilde(J - d, eps).da) / (2 * d), alpha_tilde(J, eps).d2a,
                1e-5 * std::abs(alpha_tilde(J, eps).d2a));
  }
}
