// The energy behind Macklin and Müller's (2021) constraint pair, their eqs. (9)-(13):
// deviatoric C_D = sqrt(I_C) with stiffness mu, hydrostatic C_H = J - gamma with stiffness lambda',
//   W = mu/2 (I_C - 3) + lambda'/2 (J - gamma)^2,   lambda' = lambda + mu,  gamma = 1 + mu / lambda'.
// The constant -3 mu/2 makes W vanish at rest; gamma makes P vanish there: mu + lambda'(1 - gamma) = 0.
#include "isochor/models/material.hpp"

namespace isochor {
namespace {
class XpbdPair : public Material {
 public:
  XpbdPair(double mu, double lambda) : mu_(mu), lambda_(lambda + mu), gamma_(1.0 + mu / (lambda + mu)) {}
  std::string name() const override { return "xpbd_pair"; }
  InvariantDerivatives invariants(double I, double J) const override {
    const double d = J - gamma_;
    return {0.5 * mu_ * (I - 3.0) + 0.5 * lambda_ * d * d - 0.5 * lambda_ * (1 - gamma_) * (1 - gamma_),
            0.5 * mu_,
            lambda_ * d,
            0.0,
            0.0,
            lambda_};
  }

 private:
  double mu_, lambda_, gamma_;
};
}  // namespace

std::unique_ptr<Material> make_xpbd_pair(double mu, double lambda) { return std::make_unique<XpbdPair>(mu, lambda); }

}  // namespace isochor
