// The fibre-reinforced, active muscle term (muscle.hpp has the formulas and their source).
#include "isochor/models/muscle.hpp"

#include <cmath>

namespace isochor {

namespace {
// G(u) = integral of f_L from 0.4 to u, piece by piece.
double force_length_antiderivative(double u) {
  constexpr double G06 = 0.024;                                // 3 (0.6 - 0.4)^3
  constexpr double G14 = G06 + 0.8 - 4.0 / 3.0 * 2.0 * 0.064;  // + (1.4 - 0.6) + 4/3 ((1 - 1.4)^3 - 0.4^3)
  if (u <= 0.4) return 0.0;
  if (u <= 0.6) return 3.0 * std::pow(u - 0.4, 3);
  if (u < 1.4) return G06 + (u - 0.6) + 4.0 / 3.0 * (std::pow(1.0 - u, 3) - 0.064);
  if (u <= 1.6) return G14 + 3.0 * (std::pow(u - 1.6, 3) + 0.008);
  return G14 + 0.024;
}
}  // namespace

ForceLength force_length(double u) {
  ForceLength r{0.0, 0.0, force_length_antiderivative(u) - force_length_antiderivative(1.0)};
  if (u >= 0.4 && u <= 0.6) {
    r.f = 9.0 * (u - 0.4) * (u - 0.4);
    r.df = 18.0 * (u - 0.4);
  } else if (u > 0.6 && u < 1.4) {
    r.f = 1.0 - 4.0 * (1.0 - u) * (1.0 - u);
    r.df = 8.0 * (1.0 - u);
  } else if (u >= 1.4 && u <= 1.6) {
    r.f = 9.0 * (u - 1.6) * (u - 1.6);
    r.df = 18.0 * (u - 1.6);
  }
  return r;
}

FibreEnergy fibre_energy(const MuscleLaw& m, double activation, double I4) {
  FibreEnergy e{0.0, 0.0, 0.0};
  // Active: A(lambda) = sigma_max lambda_ofl (G(lambda / lambda_ofl) - G(1 / lambda_ofl)), A' = sigma_max f_L,
  // A'' = sigma_max f_L' / lambda_ofl; in I4 = lambda^2: psi' = A' / (2 lambda), psi'' = (A'' lambda - A') / (4
  // lambda^3).
  const double lambda = std::sqrt(std::max(I4, 0.0));
  if (activation != 0.0 && lambda > 0.0) {
    const double L = m.optimal_stretch, s = m.sigma_max * activation;
    const ForceLength at = force_length(lambda / L), rest = force_length(1.0 / L);
    const double A = s * L * (at.integral - rest.integral), dA = s * at.f, d2A = s * at.df / L;
    e.psi += A;
    e.d1 += dA / (2.0 * lambda);
    e.d2 += (d2A * lambda - dA) / (4.0 * lambda * lambda * lambda);
  }
  // Passive, tension only: k1 / (2 k2) (exp(k2 d^2) - 1), d = I4 - 1 > 0 (k1 d^2 / 2 for k2 = 0).
  const double d = I4 - 1.0;
  if (m.k1 > 0.0 && d > 0.0) {
    const double x = std::exp(m.k2 * d * d);
    e.psi += m.k2 > 0.0 ? m.k1 / (2.0 * m.k2) * (x - 1.0) : 0.5 * m.k1 * d * d;
    e.d1 += m.k1 * d * x;
    e.d2 += m.k1 * x * (1.0 + 2.0 * m.k2 * d * d);
  }
  return e;
}

double fibre_stress(const MuscleLaw& m, double activation, double stretch) {
  return 2.0 * stretch * fibre_energy(m, activation, stretch * stretch).d1;
}

Mat3 fibre_stress_tensor(const MuscleLaw& m, double activation, const Vec3& a0, const Mat3& F, double* psi) {
  const Vec3 Fa = F * a0;
  const FibreEnergy e = fibre_energy(m, activation, Fa.squaredNorm());
  if (psi) *psi = e.psi;
  return (2.0 * e.d1) * Fa * a0.transpose();
}

double fibre_tet_energy(const MuscleLaw& m, double activation, const Vec3& a0, const TetShape& s, const Vec12& x,
                        Vec12* grad, Mat12* hess, const Vec12* dir, Vec12* hess_dir) {
  const Vec3 Fa = s.F(x) * a0;
  const FibreEnergy e = fibre_energy(m, activation, Fa.squaredNorm());
  const double V = s.rest_volume;
  // w_a = b_a . a0: b_1..b_3 are the rows of Dm^-1, b_0 minus their sum.
  const Vec3 w3 = s.Dm_inv * a0;
  const double w[4] = {-w3.sum(), w3[0], w3[1], w3[2]};
  if (grad)
    for (int a = 0; a < 4; ++a) grad->segment<3>(3 * a) = (2.0 * V * e.d1 * w[a]) * Fa;
  if (hess || hess_dir) {
    const Mat3 B = V * (4.0 * e.d2 * Fa * Fa.transpose() + 2.0 * e.d1 * Mat3::Identity());
    if (hess)
      for (int a = 0; a < 4; ++a)
        for (int c = 0; c < 4; ++c) hess->block<3, 3>(3 * a, 3 * c) = (w[a] * w[c]) * B;
    if (hess_dir) {
      Vec3 sum = Vec3::Zero();
      for (int c = 0; c < 4; ++c) sum += w[c] * dir->segment<3>(3 * c);
      const Vec3 Bs = B * sum;
      for (int a = 0; a < 4; ++a) hess_dir->segment<3>(3 * a) = w[a] * Bs;
    }
  }
  return V * e.psi;
}

}  // namespace isochor
