// UNH: the Bonet-Wood neo-Hookean energy, CNH paper eq. (4):
//   W = mu/2 (I_C - 3) - mu log J + lambda/2 (log J)^2,   defined for J > 0 only.
#include <cmath>
#include <limits>

#include "isochor/models/material.hpp"

namespace isochor {
namespace {
class Unh : public Material {
 public:
  Unh(double mu, double lambda) : mu_(mu), lambda_(lambda) {}
  std::string name() const override { return "unh"; }
  bool invertible() const override { return false; }
  InvariantDerivatives invariants(double I, double J) const override {
    if (!(J > 0)) {
      const double nan = std::numeric_limits<double>::quiet_NaN();
      return {std::numeric_limits<double>::infinity(), nan, nan, nan, nan, nan};
    }
    const double L = std::log(J);
    return {0.5 * mu_ * (I - 3.0) - mu_ * L + 0.5 * lambda_ * L * L,
            0.5 * mu_,
            (lambda_ * L - mu_) / J,
            0.0,
            0.0,
            (lambda_ * (1.0 - L) + mu_) / (J * J)};
  }

 private:
  double mu_, lambda_;
};
}  // namespace

std::unique_ptr<Material> make_unh(double mu, double lambda) { return std::make_unique<Unh>(mu, lambda); }

}  // namespace isochor
