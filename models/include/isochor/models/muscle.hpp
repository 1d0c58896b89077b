// Muscle: a fibre-reinforced, active term added to a tet's isotropic material (the volumetric
// behaviour stays with the material and the zone constraints, as for CNH).
//
// The fibre is a unit direction a0 in the rest configuration; its stretch is lambda = |F a0|,
// I4 = a0 . C a0 = lambda^2. The along-fibre nominal stress (force per rest area across the fibre)
// is, after Blemker, Pinsky and Delp 2005 (their eqs. 9-10, the passive part in the
// Holzapfel-Gasser-Ogden form):
//   T(lambda) = sigma_max a f_L(lambda / lambda_ofl)  +  2 lambda k1 (I4 - 1) exp(k2 (I4 - 1)^2)  [I4 > 1]
// with the activation a in [0, 1] and Blemker's piecewise quadratic force-length relation
//   f_L(u) = 9 (u - 0.4)^2       0.4 <= u <= 0.6
//            1 - 4 (1 - u)^2     0.6 <  u <  1.4
//            9 (u - 1.6)^2       1.4 <= u <= 1.6,   0 outside [0.4, 1.6].
// The energy density is psi(I4) = integral of T from 1 to lambda (the passive part
// k1 / (2 k2) (exp(k2 (I4 - 1)^2) - 1), tension only), so that
//   P = 2 psi' F a0 a0^T,  dP/dF = 4 psi'' vec(F a0 a0^T) vec(F a0 a0^T)^T + 2 psi' (a0 a0^T kron I3)
// (psi' = dpsi/dI4) and, per tet with the shape gradients b_a and w_a = b_a . a0, the gradient at
// node a is V 2 psi' w_a F a0 and the Hessian block (a, c) is V w_a w_c (4 psi'' F a0 (F a0)^T + 2 psi' I).
#pragma once
#include <vector>

#include "isochor/models/drivers.hpp"
#include "isochor/models/elements.hpp"

namespace isochor {

struct MuscleLaw {
  double sigma_max = 3.0e5;      // Pa: peak isometric stress at full activation (Blemker et al.: 300 kPa)
  double optimal_stretch = 1.0;  // lambda_ofl: the fibre stretch of peak active force
  double k1 = 0.0;               // Pa: passive fibre stiffness (tension only); 0: no passive fibre
  double k2 = 0.0;               // passive exponent; 0: k1 / 2 (I4 - 1)^2
};

// f_L(u), its derivative and its integral from 1 (so that the active energy vanishes at u = 1).
struct ForceLength {
  double f, df, integral;
};
ForceLength force_length(double u);

// The fibre energy density as a function of I4 at activation a, and its first two derivatives in I4.
struct FibreEnergy {
  double psi, d1, d2;
};
FibreEnergy fibre_energy(const MuscleLaw& m, double activation, double I4);
// The along-fibre nominal stress T(lambda) = dpsi/dlambda (the one-dimensional law).
double fibre_stress(const MuscleLaw& m, double activation, double stretch);

// V psi(|F a0|^2) of one tet, with its gradient, Hessian and H dir (each optional).
double fibre_tet_energy(const MuscleLaw& m, double activation, const Vec3& a0, const TetShape& s, const Vec12& x,
                        Vec12* grad, Mat12* hess, const Vec12* dir = nullptr, Vec12* hess_dir = nullptr);
// The fibre term's first Piola stress 2 psi' F a0 a0^T at F (psi into *psi when asked).
Mat3 fibre_stress_tensor(const MuscleLaw& m, double activation, const Vec3& a0, const Mat3& F, double* psi = nullptr);

// The muscles of a body: per tet (mesh order) the muscle it belongs to (-1: none) and its unit
// rest fibre direction; per muscle its law.
struct FibreField {
  std::vector<MuscleLaw> muscles;
  std::vector<int> muscle_of;
  std::vector<Vec3> direction;
  bool empty() const { return muscles.empty(); }
};

class Skeleton;

// A muscle's activation in time: a constant, keyframes in time, a table of a skeleton joint's
// angle (the curve's times then hold the angles, rad) or a table of a BVH channel's value (the
// curve's times hold the channel's values, as the file writes them), each times `scale`,
// clamped to [0, 1].
struct ActivationCurve {
  enum class Source { constant, time, joint, channel };
  Source source = Source::constant;
  double value = 0.0;  // constant
  Driver curve;        // keyframes: the activation in x of its values
  int bone = -1;       // joint: the bone whose joint angle keys the curve
  int axis = 0;        // joint: which of its angles (0 for a pin)
  Driver channel;      // channel: the BVH channel's value in x against time (one key per frame)
  double at(double t, const Skeleton* skeleton, double scale) const;
  // The joint angle that keys the curve at t (rad).
  double joint_angle(double t, const Skeleton& skeleton) const;
};

// The Laplace fibre field of a fusiform muscle: u solves the Laplace equation on `tets` (linear
// tets) with u = 0 on `origin` and 1 on `insertion` (nodes); each tet's fibre is grad u / |grad u|,
// and where grad u vanishes, the direction from the origin's centroid to the insertion's.
// Returns the direction per tet of `tets`, in their order.
std::vector<Vec3> laplace_fibres(const Mesh& mesh, const std::vector<int>& tets, const std::vector<int>& origin,
                                 const std::vector<int>& insertion);

}  // namespace isochor
