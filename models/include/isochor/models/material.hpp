// Hyperelastic materials as energy densities of the deformation gradient F.
//
// Every model here is a function of the two invariants I_C = tr(F^T F) and J = det F:
// psi(F) = W(I_C, J). A model supplies W and its first and second partial derivatives; the
// common code turns them into the first Piola-Kirchhoff stress and its derivative:
//   P      = 2 W_I F + W_J cof(F)                       (cof F = dJ/dF = J F^-T)
//   dP/dF  = 2 W_I 1 + 4 W_II f f^T + 2 W_IJ (f c^T + c f^T) + W_JJ c c^T + W_J d2J/dF2
// with f = vec(F), c = vec(cof F), vec column-major (entry (i, j) at 3 j + i).
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <string>

namespace isochor {

using Mat3 = Eigen::Matrix3d;
// The cross-product matrix: skew(a) b = a x b.
inline Mat3 skew(const Eigen::Vector3d& a) {
  Mat3 s;
  s << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return s;
}
using Mat9 = Eigen::Matrix<double, 9, 9>;
using Vec9 = Eigen::Matrix<double, 9, 1>;

struct InvariantDerivatives {
  double W = 0, W_I = 0, W_J = 0, W_II = 0, W_IJ = 0, W_JJ = 0;
};

// The local compression penalty of the CNH paper, eq. (13)-(15):
// U(J; beta) = (J-1)^2 [beta (J-1)^2 + 6] / 12, U' = (J-1)[beta (J-1)^2 + 3] / 3, U'' = beta (J-1)^2 + 1.
struct Penalty {
  double U, dU, d2U;
};
inline Penalty penalty_U(double J, double beta) {
  const double d = J - 1.0, d2 = d * d;
  return {d2 * (beta * d2 + 6.0) / 12.0, d * (beta * d2 + 3.0) / 3.0, beta * d2 + 1.0};
}

// alpha~(J) of the CNH paper, eq. (11): J^(-1/3) above epsilon, its quadratic Taylor continuation
// at epsilon below. Returns the value and the first two derivatives.
struct AlphaTilde {
  double a, da, d2a;
};
AlphaTilde alpha_tilde(double J, double epsilon);

class Material {
 public:
  virtual ~Material() = default;
  virtual InvariantDerivatives invariants(double I_C, double J) const = 0;
  // W, W_I and W_J alone (the second derivatives may be left zero): what a gradient needs. A model
  // may skip the work of its second derivatives here; the default is invariants().
  virtual InvariantDerivatives first_invariants(double I_C, double J) const { return invariants(I_C, J); }
  virtual std::string name() const = 0;
  // Whether the energy is defined for J <= 0 (UNH is not: log J).
  virtual bool invertible() const { return true; }

  double psi(const Mat3& F) const;
  Mat3 P(const Mat3& F) const;
  Mat9 dPdF(const Mat3& F) const;
  // psi, P and dP/dF at once (what the element kernels use).
  double evaluate(const Mat3& F, Mat3* P, Mat9* dPdF) const;
  // psi, P (optional) and dP = dP/dF : dF without forming dP/dF (the Rayleigh term beta K v of a
  // residual needs only this): about a fifth of the work.
  double evaluate_directional(const Mat3& F, const Mat3& dF, Mat3* P, Mat3& dP) const;
  // Pressure from the stress: minus the mean normal Cauchy stress, -tr(P F^T) / (3 J).
  double pressure(const Mat3& F) const;
};

// UNH, Bonet and Wood: mu/2 (I_C - 3) - mu log J + lambda/2 (log J)^2.
std::unique_ptr<Material> make_unh(double mu, double lambda);
// SNH, Smith, de Goes and Kim 2018, eq. (14) of their paper with the Lamé re-parametrisation
// mu' = 4/3 mu, lambda' = lambda + 5/6 mu (so that it matches linear elasticity at rest):
// mu'/2 (I_C - 3) + lambda'/2 (J - a)^2 - mu'/2 log(I_C + 1), a = 1 + 3 mu' / (4 lambda').
std::unique_ptr<Material> make_snh(double mu, double lambda);
// CNH, Sheen, Larionov and Pai 2021: mu/2 (alpha~(J)^2 I_C - 3) + lambda U(J; beta).
std::unique_ptr<Material> make_cnh(double mu, double lambda, double beta, double epsilon);
// The energy of Macklin and Müller's constraint pair: deviatoric C_D = sqrt(I_C) with compliance
// 1/mu, hydrostatic C_H = J - gamma with compliance 1/lambda', gamma = 1 + mu/lambda',
// lambda' = lambda + mu (their rest-stability shift): mu/2 (I_C - 3) + lambda'/2 (J - gamma)^2.
std::unique_ptr<Material> make_xpbd_pair(double mu, double lambda);

// cof F = dJ/dF, column by column: (f1 x f2, f2 x f0, f0 x f1); J = f0 . (f1 x f2).
inline Mat3 cofactor(const Mat3& F) {
  Mat3 C;
  C.col(0) = F.col(1).cross(F.col(2));
  C.col(1) = F.col(2).cross(F.col(0));
  C.col(2) = F.col(0).cross(F.col(1));
  return C;
}
// vec(cof F) and the Hessian of det F (the derivative of vec(cof F)).
Vec9 cofactor_vec(const Mat3& F);
Mat9 det_hessian(const Mat3& F);

}  // namespace isochor
