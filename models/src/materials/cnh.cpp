// CNH: the constrained neo-Hookean of Sheen, Larionov and Pai (2021).
//   W = mu/2 (alpha~(J)^2 I_C - 3) + lambda U(J; beta)
// F-bar deviatoric term, eq. (12), with alpha~ of eq. (11); penalty U of eq. (13). The zone volume
// constraints are separate (constraints/zone_volume).
#include <cmath>

#include "isochor/models/material.hpp"

namespace isochor {
namespace {
class Cnh : public Material {
 public:
  Cnh(double mu, double lambda, double beta, double eps) : mu_(mu), lambda_(lambda), beta_(beta), eps_(eps) {}
  std::string name() const override { return "cnh"; }
  InvariantDerivatives invariants(double I, double J) const override {
    const AlphaTilde a = alpha_tilde(J, eps_);
    const Penalty u = penalty_U(J, beta_);
    const double a2 = a.a * a.a;
    const double da2 = 2.0 * a.a * a.da, d2a2 = 2.0 * (a.da * a.da + a.a * a.d2a);
    return {0.5 * mu_ * (a2 * I - 3.0) + lambda_ * u.U,
            0.5 * mu_ * a2,
            0.5 * mu_ * da2 * I + lambda_ * u.dU,
            0.0,
            0.5 * mu_ * da2,
            0.5 * mu_ * d2a2 * I + lambda_ * u.d2U};
  }
  InvariantDerivatives first_invariants(double I, double J) const override {
    if (!(J > eps_)) return invariants(I, J);
    // alpha = J^(-1/3) without alpha_tilde's second derivative: d(alpha^2)/dJ = -2 alpha^2 / (3 J).
    const double r = 1.0 / J, a = std::cbrt(r), a2 = a * a;
    const Penalty u = penalty_U(J, beta_);
    return {0.5 * mu_ * (a2 * I - 3.0) + lambda_ * u.U, 0.5 * mu_ * a2, -mu_ / 3.0 * a2 * r * I + lambda_ * u.dU};
  }

 private:
  double mu_, lambda_, beta_, eps_;
};
}  // namespace

std::unique_ptr<Material> make_cnh(double mu, double lambda, double beta, double epsilon) {
  return std::make_unique<Cnh>(mu, lambda, beta, epsilon);
}

}  // namespace isochor
