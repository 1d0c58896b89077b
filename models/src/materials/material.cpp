#include <Eigen/Dense>
#include <cmath>

#include "isochor/models/material.hpp"

namespace isochor {

namespace {
Vec9 vec(const Mat3& A) { return Eigen::Map<const Vec9>(A.data()); }
}  // namespace

AlphaTilde alpha_tilde(double J, double eps) {
  if (J > eps) {
    const double a = std::cbrt(1.0 / J);
    return {a, -a / (3.0 * J), 4.0 * a / (9.0 * J * J)};
  }
  const double e13 = std::cbrt(1.0 / eps);        // eps^(-1/3)
  const double e43 = e13 / eps, e73 = e43 / eps;  // eps^(-4/3), eps^(-7/3)
  const double d = J - eps;
  return {e13 - e43 * d / 3.0 + 2.0 / 9.0 * e73 * d * d, -e43 / 3.0 + 4.0 / 9.0 * e73 * d, 4.0 / 9.0 * e73};
}

Vec9 cofactor_vec(const Mat3& F) { return vec(cofactor(F)); }

Mat9 det_hessian(const Mat3& F) {
  // cof columns: c0 = f1 x f2, c1 = f2 x f0, c2 = f0 x f1; d(a x b) = -[b]x da + [a]x db.
  Mat9 H = Mat9::Zero();
  const Eigen::Vector3d f0 = F.col(0), f1 = F.col(1), f2 = F.col(2);
  H.block<3, 3>(0, 3) = -skew(f2);
  H.block<3, 3>(0, 6) = skew(f1);
  H.block<3, 3>(3, 0) = skew(f2);
  H.block<3, 3>(3, 6) = -skew(f0);
  H.block<3, 3>(6, 0) = -skew(f1);
  H.block<3, 3>(6, 3) = skew(f0);
  return H;
}

double Material::evaluate(const Mat3& F, Mat3* P, Mat9* dPdF) const {
  const double I = F.squaredNorm(), J = F.determinant();
  const InvariantDerivatives w = invariants(I, J);
  if (P || dPdF) {
    const Vec9 f = vec(F), c = cofactor_vec(F);
    if (P) *P = Eigen::Map<const Mat3>(Vec9(2.0 * w.W_I * f + w.W_J * c).data());
    if (dPdF) {
      *dPdF = 2.0 * w.W_I * Mat9::Identity() + 4.0 * w.W_II * f * f.transpose() +
              2.0 * w.W_IJ * (f * c.transpose() + c * f.transpose()) + w.W_JJ * c * c.transpose() +
              w.W_J * det_hessian(F);
    }
  }
  return w.W;
}

double Material::evaluate_directional(const Mat3& F, const Mat3& dF, Mat3* P, Mat3& dP) const {
  // dP = dP/dF : dF term by term as in evaluate(), with d = vec(dF) and the derivative of cof F
  // along dF (columns: d(f1 x f2) = df1 x f2 + f1 x df2, ...) in place of det_hessian(F) d.
  const double I = F.squaredNorm(), J = F.determinant();
  const InvariantDerivatives w = invariants(I, J);
  const Vec9 f = vec(F), c = cofactor_vec(F), d = vec(dF);
  if (P) *P = Eigen::Map<const Mat3>(Vec9(2.0 * w.W_I * f + w.W_J * c).data());
  Mat3 dC;
  dC.col(0) = dF.col(1).cross(F.col(2)) + F.col(1).cross(dF.col(2));
  dC.col(1) = dF.col(2).cross(F.col(0)) + F.col(2).cross(dF.col(0));
  dC.col(2) = dF.col(0).cross(F.col(1)) + F.col(0).cross(dF.col(1));
  const double fd = f.dot(d), cd = c.dot(d);
  Eigen::Map<Vec9>(dP.data()) = 2.0 * w.W_I * d + (4.0 * w.W_II * fd + 2.0 * w.W_IJ * cd) * f +
                                (2.0 * w.W_IJ * fd + w.W_JJ * cd) * c + w.W_J * vec(dC);
  return w.W;
}

double Material::psi(const Mat3& F) const { return evaluate(F, nullptr, nullptr); }
Mat3 Material::P(const Mat3& F) const {
  Mat3 p;
  evaluate(F, &p, nullptr);
  return p;
}
Mat9 Material::dPdF(const Mat3& F) const {
  Mat9 d;
  evaluate(F, nullptr, &d);
  return d;
}
double Material::pressure(const Mat3& F) const { return -(P(F) * F.transpose()).trace() / (3.0 * F.determinant()); }

}  // namespace isochor
