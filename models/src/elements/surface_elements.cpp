// Surface triangles (the epidermis), springs, and the ground plane.
#include <Eigen/Dense>
#include <cmath>

#include "isochor/models/elements.hpp"
#include "isochor/models/material.hpp"

namespace isochor {

double triangle_area(const Vec9n& x, Vec9n* grad, Mat9n* hess) {
  // n = (x1 - x0) x (x2 - x0), A = |n| / 2. dn = -[e2]x de1 + [e1]x de2 with e1 = x1 - x0, e2 = x2 - x0.
  const Vec3 e1 = x.segment<3>(3) - x.segment<3>(0), e2 = x.segment<3>(6) - x.segment<3>(0);
  const Vec3 n = e1.cross(e2);
  const double len = n.norm();
  if (!grad && !hess) return 0.5 * len;
  Eigen::Matrix<double, 3, 9> dn;  // dn/dx
  const Mat3 s1 = skew(e1), s2 = skew(e2);
  dn.block<3, 3>(0, 3) = -s2;
  dn.block<3, 3>(0, 6) = s1;
  dn.block<3, 3>(0, 0) = s2 - s1;
  const Vec3 nh = n / len;
  if (grad) *grad = 0.5 * dn.transpose() * nh;
  if (hess) {
    // A'' = 1/2 [dn^T (I - nh nh^T)/|n| dn + sum_i nh_i d2n_i]; d2(n . w) for fixed w:
    // n . w = e1 . (e2 x w) so d2/de1 de2 = -[w]x ... from n.w = e1^T [e2]x^T w = -e1^T [w]x e2...
    Mat9n H = dn.transpose() * (Mat3::Identity() - nh * nh.transpose()) / len * dn;
    // n . w = (e1 x e2) . w = e1 . (e2 x w) = e1^T [e2]x w = -e1^T [w]x e2, so d2/de1de2 = -[w]x.
    Eigen::Matrix<double, 6, 6> He = Eigen::Matrix<double, 6, 6>::Zero();
    He.block<3, 3>(0, 3) = -skew(nh);
    He.block<3, 3>(3, 0) = skew(nh);  // transpose of -[w]x
    Eigen::Matrix<double, 6, 9> D = Eigen::Matrix<double, 6, 9>::Zero();
    D.block<3, 3>(0, 0) = -Mat3::Identity();
    D.block<3, 3>(0, 3) = Mat3::Identity();
    D.block<3, 3>(3, 0) = -Mat3::Identity();
    D.block<3, 3>(3, 6) = Mat3::Identity();
    H += D.transpose() * He * D;
    *hess = 0.5 * H;
  }
  return 0.5 * len;
}

double epidermis_energy(double A0, double lambda_e, double gamma, const Vec9n& x, Vec9n* grad, Mat9n* hess) {
  Vec9n dA;
  Mat9n d2A;
  const double A = triangle_area(x, (grad || hess) ? &dA : nullptr, hess ? &d2A : nullptr);
  const Penalty u = penalty_U(A / A0, gamma);
  if (grad) *grad = lambda_e * u.dU * dA;
  if (hess) *hess = lambda_e * (u.d2U / A0 * dA * dA.transpose() + u.dU * d2A);
  return A0 * lambda_e * u.U;
}

double spring_energy(double k, double L, const Vec6& x, Vec6* grad, Mat6* hess) {
  const Vec3 d = x.segment<3>(3) - x.segment<3>(0);
  const double len = d.norm(), ext = len - L;
  const Vec3 dh = d / len;
  if (grad) {
    grad->segment<3>(3) = k * ext * dh;
    grad->segment<3>(0) = -k * ext * dh;
  }
  if (hess) {
    const Mat3 K = k * (dh * dh.transpose() + ext / len * (Mat3::Identity() - dh * dh.transpose()));
    hess->block<3, 3>(0, 0) = K;
    hess->block<3, 3>(3, 3) = K;
    hess->block<3, 3>(0, 3) = -K;
    hess->block<3, 3>(3, 0) = -K;
  }
  return 0.5 * k * ext * ext;
}

Vec6 spring_damping_force(double c, const Vec6& x, const Vec6& v, Mat6* df_dx, Mat6* df_dv) {
  const Vec3 d = x.segment<3>(3) - x.segment<3>(0);
  const double len = d.norm();
  const Vec3 dh = d / len;
  const Vec3 w = v.segment<3>(0) - v.segment<3>(3);
  const Vec3 f0 = -c * dh * dh.dot(w);
  Vec6 f;
  f << f0, -f0;
  const Mat3 Pd = dh * dh.transpose();
  if (df_dv) {
    df_dv->block<3, 3>(0, 0) = -c * Pd;
    df_dv->block<3, 3>(0, 3) = c * Pd;
    df_dv->block<3, 3>(3, 0) = c * Pd;
    df_dv->block<3, 3>(3, 3) = -c * Pd;
  }
  if (df_dx) {
    // d(dh (dh . w))/dd = [(dh . w) I + dh w^T] (I - dh dh^T) / |d|, and dd/dx0 = -I, dd/dx1 = I.
    const Mat3 G = -c * (dh.dot(w) * Mat3::Identity() + dh * w.transpose()) * (Mat3::Identity() - Pd) / len;
    df_dx->block<3, 3>(0, 0) = -G;
    df_dx->block<3, 3>(0, 3) = G;
    df_dx->block<3, 3>(3, 0) = G;
    df_dx->block<3, 3>(3, 3) = -G;
  }
  return f;
}

double contact_energy(double k, double delta, double s, const Vec3& n, const Mat3& H, Vec3* grad, Mat3* hess) {
  const double p = delta - s;
  if (p <= 0) {
    if (grad) grad->setZero();
    if (hess) hess->setZero();
    return 0.0;
  }
  if (grad) *grad = -k * p * p * n;
  if (hess) *hess = 2.0 * k * p * n * n.transpose() - k * p * p * H;
  return k / 3.0 * p * p * p;
}

Vec3 contact_damping_force(double k, double alpha, double mu_c, double eps, double delta, double s, const Vec3& n,
                           const Mat3& H, const Vec3& v_rel, const Mat3& dvrel_dx, Mat3* neg_dfdx, Mat3* neg_dfdv) {
  const double p = delta - s;
  if (neg_dfdx) neg_dfdx->setZero();
  if (neg_dfdv) neg_dfdv->setZero();
  if (p <= 0) return Vec3::Zero();
  Vec3 f = Vec3::Zero();
  const double sdot = n.dot(v_rel);
  // d sdot / dx = v_rel^T H + n^T dvrel_dx (a row).
  const Vec3 dsdot = H * v_rel + dvrel_dx.transpose() * n;
  if (alpha > 0) {
    const double c = k * alpha;
    f -= c * p * p * sdot * n;
    // f = -c p^2 sdot n with dp/dx = -n^T, dn/dx = H.
    if (neg_dfdx)
      *neg_dfdx += c * (-2.0 * p * sdot * n * n.transpose() + p * p * n * dsdot.transpose() + p * p * sdot * H);
    if (neg_dfdv) *neg_dfdv += c * p * p * n * n.transpose();
  }
  if (mu_c > 0) {
    const Mat3 T = Mat3::Identity() - n * n.transpose();
    const Vec3 u = T * v_rel;
    const double r = std::sqrt(u.squaredNorm() + eps * eps), fn = k * p * p;
    const Vec3 phi = u / r;
    const Mat3 Dphi = (Mat3::Identity() - u * u.transpose() / (r * r)) / r;
    f -= mu_c * fn * phi;
    // du/dx = T dvrel_dx - sdot H - n (H v_rel)^T; d fn/dx = -2 k p n^T.
    if (neg_dfdx)
      *neg_dfdx += mu_c * (-2.0 * k * p * phi * n.transpose() +
                           fn * Dphi * (T * dvrel_dx - sdot * H - n * (H * v_rel).transpose()));
    if (neg_dfdv) *neg_dfdv += mu_c * fn * Dphi * T;
  }
  return f;
}

double ground_energy(double k, double delta, const Vec3& point, const Vec3& normal, const Vec3& x, Vec3* grad,
                     Mat3* hess) {
  return contact_energy(k, delta, (x - point).dot(normal), normal, Mat3::Zero(), grad, hess);
}

Vec3 ground_damping_force(double k, double alpha, double delta, const Vec3& point, const Vec3& normal, const Vec3& x,
                          const Vec3& v_rel, Mat3* neg_dfdx, Mat3* neg_dfdv) {
  return contact_damping_force(k, alpha, 0.0, 0.0, delta, (x - point).dot(normal), normal, Mat3::Zero(), v_rel,
                               Mat3::Zero(), neg_dfdx, neg_dfdv);
}

}  // namespace isochor
