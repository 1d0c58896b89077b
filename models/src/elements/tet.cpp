// The linear tetrahedron: maps any material to nodes through the constant matrix dF/dx.
#include "isochor/models/elements.hpp"

#include <Eigen/Dense>

namespace isochor {

TetShape TetShape::make(const Vec3& X0, const Vec3& X1, const Vec3& X2, const Vec3& X3) {
  TetShape s;
  Mat3 Dm;
  Dm << X1 - X0, X2 - X0, X3 - X0;
  s.Dm_inv = Dm.inverse();
  s.rest_volume = Dm.determinant() / 6.0;
  return s;
}

Mat3 TetShape::F(const Vec12& x) const {
  Mat3 Ds;
  Ds << x.segment<3>(3) - x.segment<3>(0), x.segment<3>(6) - x.segment<3>(0), x.segment<3>(9) - x.segment<3>(0);
  return Ds * Dm_inv;
}

namespace {
// Shape gradients b_a of the four nodes: F = sum_a x_a b_a^T (b_1..b_3 the rows of Dm^-1, b_0
// minus their sum), so dF/dx_{a,i} = e_i b_a^T. The products with dFdx below use this structure
// (27 multiplications for a gradient instead of 108 for the dense 12 x 9 product).
inline void shape_gradients(const Mat3& Dm_inv, Vec3 b[4]) {
  for (int a = 1; a <= 3; ++a) b[a] = Dm_inv.row(a - 1).transpose();
  b[0] = -(b[1] + b[2] + b[3]);
}
}  // namespace

Vec12 TetShape::scatter(const Mat3& P) const {
  // dFdx^T vec(P): node a gets P b_a.
  const Mat3 G = P * Dm_inv.transpose();
  Vec12 g;
  g.segment<3>(3) = G.col(0);
  g.segment<3>(6) = G.col(1);
  g.segment<3>(9) = G.col(2);
  g.segment<3>(0) = -(G.col(0) + G.col(1) + G.col(2));
  return g;
}

Mat12 TetShape::pull_back(const Mat9& A) const {
  // dFdx^T A dFdx, entry ((a,i),(c,k)) = sum_{j,l} b_a[j] A(3j+i, 3l+k) b_c[l].
  Vec3 b[4];
  shape_gradients(Dm_inv, b);
  Eigen::Matrix<double, 9, 12> T;  // A dFdx: column (c,k) = sum_l A.col(3l+k) b_c[l]
  for (int c = 0; c < 4; ++c)
    for (int k = 0; k < 3; ++k) T.col(3 * c + k) = A.col(k) * b[c][0] + A.col(3 + k) * b[c][1] + A.col(6 + k) * b[c][2];
  Mat12 H;
  for (int a = 0; a < 4; ++a)
    for (int i = 0; i < 3; ++i) H.row(3 * a + i) = b[a][0] * T.row(i) + b[a][1] * T.row(3 + i) + b[a][2] * T.row(6 + i);
  return H;
}

double tet_energy(const Material& m, const TetShape& s, const Vec12& x, Vec12* grad, Mat12* hess, const Vec12* dir,
                  Vec12* hess_dir) {
  Mat3 P;
  if (hess_dir && !hess) {
    // H d without forming H or dP/dF: dF = F(d), dP = dP/dF : dF, then scattered like a gradient.
    Mat3 dP;
    const double psi = m.evaluate_directional(s.F(x), s.F(*dir), grad ? &P : nullptr, dP);
    if (grad) *grad = s.rest_volume * s.scatter(P);
    *hess_dir = s.rest_volume * s.scatter(dP);
    return s.rest_volume * psi;
  }
  if (!hess) {
    const double psi = m.evaluate(s.F(x), grad ? &P : nullptr, nullptr);
    if (grad) *grad = s.rest_volume * s.scatter(P);
    return s.rest_volume * psi;
  }
  // The Hessian term by term (material.hpp: dP/dF = 2 W_I 1 + 4 W_II f f^T + 2 W_IJ (f c^T +
  // c f^T) + W_JJ c c^T + W_J d2J/dF2), each pulled back through dF/dx without the 9x9 matrix:
  //   2 W_I 1        ->  2 W_I (b_a . b_c) I3 in block (a, c)
  //   u v^T          ->  scatter(u) scatter(v)^T (12 x 12 outer products)
  //   W_J d2J/dF2    ->  W_J sum_{j,l} b_a[j] b_c[l] eps_ikm eps_jln F_mn = -W_J skew(F (b_a x b_c)),
  //                      zero for a = c.
  const Mat3 F = s.F(x);
  const InvariantDerivatives w = m.invariants(F.squaredNorm(), F.determinant());
  const Mat3 C = cofactor(F);  // dJ/dF
  const double V = s.rest_volume;
  const Vec12 gf = s.scatter(F), gc = s.scatter(C);
  if (grad) *grad = V * (2.0 * w.W_I * gf + w.W_J * gc);
  Vec3 b[4];
  shape_gradients(s.Dm_inv, b);
  Mat12& H = *hess;
  H.noalias() = (V * 4.0 * w.W_II) * gf * gf.transpose();
  H.noalias() += (V * 2.0 * w.W_IJ) * (gf * gc.transpose() + gc * gf.transpose());
  H.noalias() += (V * w.W_JJ) * gc * gc.transpose();
  const double di = V * 2.0 * w.W_I, dj = V * w.W_J;
  for (int a = 0; a < 4; ++a) {
    for (int i = 0; i < 3; ++i) H(3 * a + i, 3 * a + i) += di * b[a].squaredNorm();
    for (int c = a + 1; c < 4; ++c) {
      const double bb = di * b[a].dot(b[c]);
      const Mat3 K = dj * skew(F * b[a].cross(b[c]));
      H.block<3, 3>(3 * a, 3 * c) += bb * Mat3::Identity() - K;
      H.block<3, 3>(3 * c, 3 * a) += bb * Mat3::Identity() + K;
    }
  }
  if (hess_dir) *hess_dir = H * *dir;
  return V * w.W;
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
    Eigen::Matrix<double, 9, 9> Hv = Eigen::Matrix<double, 9, 9>::Zero();
    // d/dv2 of (v2 x v3) . w  etc.: d2V/dv1 dv2 = -[v3]x / 6 ... from V = v1^T [v2]x v3 / 6.
    Hv.block<3, 3>(0, 3) = -skew(v3) / 6.0;  // d2V / dv1 dv2
    Hv.block<3, 3>(0, 6) = skew(v2) / 6.0;   // d2V / dv1 dv3
    Hv.block<3, 3>(3, 6) = -skew(v1) / 6.0;  // d2V / dv2 dv3
    Hv.block<3, 3>(3, 0) = Hv.block<3, 3>(0, 3).transpose();
    Hv.block<3, 3>(6, 0) = Hv.block<3, 3>(0, 6).transpose();
    Hv.block<3, 3>(6, 3) = Hv.block<3, 3>(3, 6).transpose();
    // Chain rule through v_k = x_k - x_0 without the dense 12 x 9 products: the block of nodes
    // (k, l) is Hv(k-1, l-1), node 0's blocks are minus the sums over the others.
    Mat12& H = *hess;
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l < 3; ++l) H.block<3, 3>(3 * (k + 1), 3 * (l + 1)) = Hv.block<3, 3>(3 * k, 3 * l);
    for (int l = 1; l < 4; ++l) {
      H.block<3, 3>(0, 3 * l) = -(H.block<3, 3>(3, 3 * l) + H.block<3, 3>(6, 3 * l) + H.block<3, 3>(9, 3 * l));
      H.block<3, 3>(3 * l, 0) = H.block<3, 3>(0, 3 * l).transpose();
    }
    H.block<3, 3>(0, 0) = -(H.block<3, 3>(0, 3) + H.block<3, 3>(0, 6) + H.block<3, 3>(0, 9));
  }
  return v1.dot(v2.cross(v3)) / 6.0;
}

}  // namespace isochor
