// The linear tetrahedron: maps any material to nodes through the constant matrix dF/dx.
#include "isochor/elements.hpp"

#include <Eigen/Dense>

namespace isochor {

TetShape TetShape::make(const Vec3& X0, const Vec3& X1, const Vec3& X2, const Vec3& X3) {
  TetShape s;
  Mat3 Dm;
  Dm << X1 - X0, X2 - X0, X3 - X0;
  s.Dm_inv = Dm.inverse();
  s.rest_volume = Dm.determinant() / 6.0;
  // F_ij = sum_k (x_k - x_0)_i B_kj, B = Dm^-1, k = 1..3: dF_ij/dx_{k,i} = B_{k-1,j}.
  s.dFdx.setZero();
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      const int row = 3 * j + i;
      double sum = 0;
      for (int k = 1; k <= 3; ++k) {
        s.dFdx(row, 3 * k + i) = s.Dm_inv(k - 1, j);
        sum += s.Dm_inv(k - 1, j);
      }
      s.dFdx(row, i) = -sum;
    }
  return s;
}

Mat3 TetShape::F(const Vec12& x) const {
  Mat3 Ds;
  Ds << x.segment<3>(3) - x.segment<3>(0), x.segment<3>(6) - x.segment<3>(0), x.segment<3>(9) - x.segment<3>(0);
  return Ds * Dm_inv;
}

double tet_energy(const Material& m, const TetShape& s, const Vec12& x, Vec12* grad, Mat12* hess, const Vec12* dir,
                  Vec12* hess_dir) {
  Mat3 P;
  Mat9 dPdF;
  const bool second = hess || hess_dir;
  const double psi = m.evaluate(s.F(x), grad ? &P : nullptr, second ? &dPdF : nullptr);
  if (grad) *grad = s.rest_volume * s.dFdx.transpose() * Eigen::Map<const Vec9>(P.data());
  if (hess) *hess = s.rest_volume * s.dFdx.transpose() * dPdF * s.dFdx;
  // H d without forming H: three matrix-vector products instead of two matrix products.
  if (hess_dir) *hess_dir = s.rest_volume * (s.dFdx.transpose() * (dPdF * (s.dFdx * *dir)));
  return s.rest_volume * psi;
}

double tet_volume(const Vec12& x, Vec12* grad, Mat12* hess) {
  const Vec3 x0 = x.segment<3>(0);
  const Vec3 v1 = x.segment<3>(3) - x0, v2 = x.segment<3>(6) - x0, v3 = x.segment<3>(9) - x0;
  if (grad) {
    const Vec3 g1 = v2.cross(v3) / 6.0, g2 = v3.cross(v1) / 6.0, g3 = v1.cross(v2) / 6.0;
    grad->segment<3>(0) = -(g1 + g2 + g3);
    grad->segment<3>(3) = g1;
    grad->segment<3>(6) = g2;
    grad->segment<3>(9) = g3;
  }
  if (hess) {
    // V = v1 . (v2 x v3) / 6 is trilinear in (v1, v2, v3): d2V/dv_a dv_b = skew matrices; then
    // the chain rule through v_k = x_k - x_0.
    auto skew = [](const Vec3& a) {
      Mat3 s;
      s << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
      return s;
    };
    Eigen::Matrix<double, 9, 9> Hv = Eigen::Matrix<double, 9, 9>::Zero();
    // d/dv2 of (v2 x v3) . w  etc.: d2V/dv1 dv2 = -[v3]x / 6 ... from V = v1^T [v2]x v3 / 6.
    Hv.block<3, 3>(0, 3) = -skew(v3) / 6.0;  // d2V / dv1 dv2
    Hv.block<3, 3>(0, 6) = skew(v2) / 6.0;   // d2V / dv1 dv3
    Hv.block<3, 3>(3, 6) = -skew(v1) / 6.0;  // d2V / dv2 dv3
    Hv.block<3, 3>(3, 0) = Hv.block<3, 3>(0, 3).transpose();
    Hv.block<3, 3>(6, 0) = Hv.block<3, 3>(0, 6).transpose();
    Hv.block<3, 3>(6, 3) = Hv.block<3, 3>(3, 6).transpose();
    Eigen::Matrix<double, 9, 12> D = Eigen::Matrix<double, 9, 12>::Zero();
    for (int k = 0; k < 3; ++k) {
      D.block<3, 3>(3 * k, 0) = -Mat3::Identity();
      D.block<3, 3>(3 * k, 3 * (k + 1)) = Mat3::Identity();
    }
    *hess = D.transpose() * Hv * D;
  }
  return v1.dot(v2.cross(v3)) / 6.0;
}

}  // namespace isochor
