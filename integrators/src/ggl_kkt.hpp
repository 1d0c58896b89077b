// IDA's Newton system of the GGL form with many constraint rows, solved through a KKT matrix of
// n + m unknowns instead of the (2n + 2m) GGL matrix. With rhs (r1, r2, r3, r4), unknowns (dq, dv,
// dl, dm), V = c M - df/dv, A = -df/dq + H_lambda, B = d(G v)/dq, S = A + c V (ggl.hpp), the
// change dq = dp - G^T dm / c makes dv = c dp - r1 (H_mu left out) and the system exactly
//   S dp + G^T dl - (A / c) G^T dm = r2 + V r1
//   (B + c G) dp  - (B / c) G^T dm = r4 + G r1
//   G dp          - (G G^T / c) dm = r3.
// Leaving out the two terms in dm / c (and H_mu) decouples it: the KKT matrix
// K1 = [S G^T; B + c G 0] (sparse LU: KktFactor, UMFPACK above kMultifrontalRows) gives (dp, dl),
// the sparse SPD G G^T then dm, and row 1 dv. That preconditioner P is refined against the GGL
// matrix itself (x += P^-1 (b - J x)) until the estimated error is below kRefineTol, so the
// solve is J's, as a factor of J would give it. The left-out terms weigh K against c^2 M: the
// refinement contracts fast at IDA's usual c_j (one step on the beam) and slowly or not at all
// at large steps on stiff contact (the test's box on a 1e8 N/m ground: 3 steps at c_j = 2e4,
// 7 at 50, none at 10); where it does not converge, J's own LU solves.
//
// Why: the GGL matrix's own factor couples each multiplier mu with the 2-ring of its row's dofs
// (through the q-rows' G^T mu and the v-rows' c M), which a KKT matrix does not. Measured on the
// clamped beam's 1-ring zones (6,480 tets, 1,516 rows, one Jacobian): K1's LU 2.9M entries
// against the GGL matrix's 19.2M (SuperLU, both in its own order); the first P^-1 b is 5% off in
// dq and 100% in dl (the left-out dm coupling), one refinement step brings it to 3e-6 of J's
// direct solution, which is that solution's own accuracy (its relative residual is 1e-5), on the
// 810- and 6,480-tet beams, with 1-ring zones and with 2-ring patches (docs/decisions.md).
#pragma once
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <memory>
#include <vector>

#include "isochor/integrators/ggl.hpp"
#include "kkt.hpp"
#include "umfpack_lu.hpp"

namespace isochor {

class GglKktSolver {
 public:
  static constexpr int kMaxRefinements = 8;
  // The estimated error of the solution, in the weighted RMS norm of IDA's Newton test, at which
  // refinement stops: 500 times below that test's tolerance (IdaOptions::kDefaultNewtonCoef,
  // 0.05), so the Newton iterations, the steps and the answer are those of a factor of J.
  static constexpr double kRefineTol = 1e-4;
  static constexpr double kRhoSafety = 10;

  explicit GglKktSolver(const GglForm& form);
  ~GglKktSolver();
  // Factors K1 and G G^T for the filled GGL matrix `values` (kept, not copied: read by solve).
  // False if either is singular.
  bool setup(double cj, const double* values);
  // x = J^-1 b, to kRefineTol in the weighted RMS norm with these weights (IDA's error weights).
  // Where the refinement does not converge within kMaxRefinements steps, J's own sparse LU
  // (UMFPACK) solves instead for the rest of the setup. False if that LU is singular.
  bool solve(const double* b, double* x, const double* weights);
  double factor_entries() const;
  long refinements() const { return refinements_; }
  long fallbacks() const { return fallbacks_; }  // setups solved by J's own LU

 private:
  bool refine(const double* b, double* x, const double* weights);                      // false: no convergence
  void precondition(const double* b, double* x);                                       // x = P^-1 b
  void block_times(const std::vector<Index>& slot, const double* x, double* y) const;  // y += X x

  const GglForm& form_;
  Index n_, m_;
  double cj_ = 0;
  const double* values_ = nullptr;
  KktLayout layout_;
  KktFactor factor_;
  std::vector<double> kv_, sx_;                // K1's values; S's (in the system's pattern)
  std::vector<std::vector<double>> g_, brow_;  // G and B + c G, per row
  Eigen::SparseMatrix<double> gs_;             // G, m x n
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ggt_;
  Eigen::VectorXd k1_, gt_dm_, dm_, r_, dx_, x_;
  long refinements_ = 0;
  double rho_ = -1;                    // the largest contraction measured since the setup (-1: none yet)
  std::unique_ptr<UmfpackLu> direct_;  // J's LU, made at the first fallback
  bool direct_ready_ = false;          // this setup solves with direct_
  long fallbacks_ = 0;                 // setups solved by direct_
};

}  // namespace isochor
