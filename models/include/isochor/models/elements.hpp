// Element kernels: value, gradient and Hessian of one element's energy (or constraint) in terms
// of its node positions, stacked node after node (x0, y0, z0, x1, ...). No kernel knows a mesh.
#pragma once
#include <Eigen/Core>

#include "isochor/models/material.hpp"

namespace isochor {

using Vec3 = Eigen::Vector3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Vec9n = Eigen::Matrix<double, 9, 1>;
using Vec12 = Eigen::Matrix<double, 12, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Mat9n = Eigen::Matrix<double, 9, 9>;
using Mat12 = Eigen::Matrix<double, 12, 12>;

// A linear tet: F = Ds Dm^-1 and the constant 9x12 map dF/dx (vec(F) column-major).
struct TetShape {
  Mat3 Dm_inv;
  double rest_volume = 0;

  static TetShape make(const Vec3& X0, const Vec3& X1, const Vec3& X2, const Vec3& X3);
  Mat3 F(const Vec12& x) const;
  // dFdx^T vec(P) (the gradient of an energy density with first Piola P, per unit volume) and
  // dFdx^T A dFdx (its Hessian for A = dP/dF), using dFdx's structure.
  Vec12 scatter(const Mat3& P) const;
  Mat12 pull_back(const Mat9& A) const;  // the generic path; tet_energy builds its Hessian term by
                                         // term, and is tested against this
};

// Energy V psi(F) of a tet; gradient V dFdx^T vec(P), Hessian V dFdx^T dP/dF dFdx (dFdx = dvec(F)/dx).
// With dir and hess_dir, also hess_dir = H dir (computed without H when hess is null).
double tet_energy(const Material& m, const TetShape& s, const Vec12& x, Vec12* grad, Mat12* hess,
                  const Vec12* dir = nullptr, Vec12* hess_dir = nullptr);

// Signed volume of a tet and its derivatives (the zone-volume constraint per element).
double tet_volume(const Vec12& x, Vec12* grad, Mat12* hess);

// Epidermis, CNH paper eq. (16): on a surface triangle of rest area A0,
// A0 lambda_e U(J~; gamma) with J~ = A / A0 (the area ratio, det of the reduced 3x2 F).
double epidermis_energy(double rest_area, double lambda_e, double gamma, const Vec9n& x, Vec9n* grad, Mat9n* hess);
double triangle_area(const Vec9n& x, Vec9n* grad, Mat9n* hess);

// Spring between two nodes: k/2 (|x1 - x0| - L)^2.
double spring_energy(double k, double rest_length, const Vec6& x, Vec6* grad, Mat6* hess);
// Spring damping force along the spring, f0 = -c (d^ d^T)(v0 - v1), f1 = -f0, with d = x1 - x0;
// its derivatives with respect to positions and velocities (6x6 each).
Vec6 spring_damping_force(double c, const Vec6& x, const Vec6& v, Mat6* df_dx, Mat6* df_dv);

// Contact with a rigid body (colliders.hpp) at a node whose signed distance to it is s, with
// gradient n = ds/dx and Hessian H = d2s/dx2 there: energy k/3 (delta - s)^3 when s < delta
// (contact thickness delta), else 0. C^2 in position where s is; gradient -k p^2 n and Hessian
// 2 k p n n^T - k p^2 H with the penetration p = delta - s.
double contact_energy(double k, double delta, double s, const Vec3& n, const Mat3& H, Vec3* grad, Mat3* hess);
// The contact's dissipative force at a node moving at v_rel relative to the body's material there
// (dv_rel/dx = -skew(omega) for a body turning at omega: pass it as dvrel_dx).
// Normal damping (Hunt & Crossley's form): with sdot = n . v_rel, f = -k alpha p^2 sdot n, the
// elastic force k p^2 times alpha sdot: C^1 in position, linear in velocity; a point mass hitting
// at speed v0 leaves at e = sqrt(1 - 4/3 alpha v0) to first order in alpha v0 (docs/scenes.md).
// Smoothed Coulomb friction: with the tangential velocity u = (I - n n^T) v_rel, f = -mu_c k p^2
// u / sqrt(|u|^2 + eps^2) (eps the slip speed: below it friction grows linearly with the speed).
// Returns f; -df/dx and -df/dv into the 3x3 blocks if asked.
Vec3 contact_damping_force(double k, double alpha, double mu_c, double eps, double delta, double s, const Vec3& n,
                           const Mat3& H, const Vec3& v_rel, const Mat3& dvrel_dx, Mat3* neg_dfdx, Mat3* neg_dfdv);

// The same for a plane through `point` with unit `normal` (s = (x - point) . normal, H = 0).
double ground_energy(double k, double delta, const Vec3& point, const Vec3& normal, const Vec3& x, Vec3* grad,
                     Mat3* hess);
Vec3 ground_damping_force(double k, double alpha, double delta, const Vec3& point, const Vec3& normal, const Vec3& x,
                          const Vec3& v_rel, Mat3* neg_dfdx, Mat3* neg_dfdv);

}  // namespace isochor
