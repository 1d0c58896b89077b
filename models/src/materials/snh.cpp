// SNH: stable neo-Hookean of Smith, de Goes and Kim (2018), their eq. (14), with the Lamé
// re-parametrisation of their Section 3.4 (mu' = 4/3 mu, lambda' = lambda + 5/6 mu):
//   W = mu'/2 (I_C - 3) + lambda'/2 (J - a)^2 - mu'/2 log(I_C + 1),  a = 1 + 3 mu' / (4 lambda').
// a makes P vanish at F = I: mu'(1 - 1/4) + lambda'(1 - a) = 0. The constant W(I) is subtracted.
#include <cmath>

#include "isochor/models/material.hpp"

namespace isochor {
namespace {
class Snh : public Material {
 public:
  Snh(double mu, double lambda)
      : mu_(4.0 / 3.0 * mu), lambda_(lambda + 5.0 / 6.0 * mu), a_(1.0 + 0.75 * mu_ / lambda_) {}
  std::string name() const override { return "snh"; }
  InvariantDerivatives invariants(double I, double J) const override {
    const double d = J - a_;
    return {0.5 * mu_ * (I - 3.0) + 0.5 * lambda_ * d * d - 0.5 * mu_ * std::log(I + 1.0) - rest_,
            0.5 * mu_ * (1.0 - 1.0 / (I + 1.0)),
            lambda_ * d,
            0.5 * mu_ / ((I + 1.0) * (I + 1.0)),
            0.0,
            lambda_};
  }

 private:
  double mu_, lambda_, a_;
  // Smith et al.'s W is not zero at rest; the constant is removed so that energies compare.
  double rest_ = 0.5 * lambda_ * (1.0 - a_) * (1.0 - a_) - 0.5 * mu_ * std::log(4.0);
};
}  // namespace

std::unique_ptr<Material> make_snh(double mu, double lambda) { return std::make_unique<Snh>(mu, lambda); }

}  // namespace isochor
