// The stabilised index-2 (GGL) form of a ConstrainedSystem, y = (q, v, lambda, mu):
//   F_q  = q' - v + G^T mu          F_v  = M v' - f(q, v, t) + G^T lambda
//   F_g  = g(q, t)                  F_gv = G v + dg/dt
// its residual, and its Jacobian dF/dy + c_j dF/dy' filled into a pattern built once:
//            q                      v             lambda   mu
//   F_q   [ c_j I + sum mu_j H_j    -I            0        G^T ]
//   F_v   [ -df/dq + sum l_j H_j    c_j M - df/dv G^T      0   ]
//   F_g   [ G                       0             0        0   ]
//   F_gv  [ d(G v)/dq               G             0        0   ]
// and a solver of the Newton system that eliminates dv and factors only the n x n effective
// stiffness S = c_j^2 M - c_j df/dv - df/dq + sum lambda_j H_j (CHOLMOD), with the 2m borders
// by a Schur complement.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "isochor/integrators/constrained_system.hpp"
#include "isochor/integrators/sparse_factor.hpp"

namespace isochor {

class GglForm {
 public:
  explicit GglForm(ConstrainedSystem& sys);
  ConstrainedSystem& system() const { return sys_; }
  Index n() const { return n_; }
  Index m() const { return m_; }
  Index size() const { return 2 * n_ + 2 * m_; }
  const SparsePattern& pattern() const { return p_; }
  // F(t, y, y'); false if an entry is not finite.
  bool residual(double t, const double* y, const double* yp, double* r);
  // values (in pattern()) = dF/dy + cj dF/dy'.
  void jacobian(double t, double cj, const double* y, const double* yp, double* values);
  // values += d dF/dy': a Jacobian filled at c_j becomes the one at c_j + d (dF/dy' is constant:
  // the diagonals I of F_q and M of F_v).
  void shift_cj(double d, double* values) const;

  // Slots of the blocks in the value array: per entry k of the system's pattern (q-q, v-q, v-v),
  // per dof (diagonals), per entry of each constraint row.
  std::vector<Index> qq, vq, vv, q_diag, v_diag, qv;
  std::vector<std::vector<Index>> gq, gvq, gvv, qmu, vlam;

 private:
  void unpack(const double* y, const double* yp);
  ConstrainedSystem& sys_;
  Index n_, m_;
  SparsePattern p_;
  VectorXd q_, v_, qd_, vd_, lambda_, mu_, f_, g_, gt_;
  std::vector<std::vector<double>> G_, Gv_;
  std::vector<double> sA_, sB_, sC_;
};

// Solves J x = b for a filled GGL Jacobian by the reduction above. The terms sum mu_j H_j are
// left out of the elimination (mu = 0 at the solution), so the solve is exact when mu = 0 and an
// approximation otherwise, which Newton's iteration absorbs.
class ReducedSolver {
 public:
  // kind: cholmod (direct) or pcg (the krylov solver: no factor; pcg_tol its relative
  // residual).
  explicit ReducedSolver(const GglForm& form, SymmetricSolverKind kind = SymmetricSolverKind::cholmod,
                         double pcg_tol = 1e-12);
  ~ReducedSolver();
  // Factors S for this Jacobian (LDL^T while S is indefinite; "pcg": CHOLMOD where PCG fails);
  // false when it is singular.
  bool setup(double cj, const double* values);
  // IDA's c_j moves between setups (the step or the order changed). A solve with the setup's c_j
  // then converges linearly (IDA scales the correction by 2 / (1 + c_j / c_j,setup), exact for a
  // first-order system, not for this one, whose S ~ c_j^2 M: ~0.2 per Newton iteration on the
  // collapse). retarget moves the setup to the new c_j: S and the borders follow without new
  // assembly, and `values` (the array given to setup, or null: IDA zeroes its matrix before each
  // setup) get their c_j I and c_j M diagonals moved. IDA uses it for a setup that reuses the
  // last Jacobian at a new c_j (jacobian_age); between setups it scales as IDA does, so that
  // every solver takes the same steps. Only where the factor of S is cheap (can_retarget: PCG,
  // not in its CHOLMOD fallback). False when S at the new c_j cannot be solved. solve(refine > 0)
  // reads the values: after retarget(cj, nullptr) only refine = 0.
  bool can_retarget() const;
  bool retarget(double cj, double* values);
  double cj() const;  // the c_j of the current setup (or retarget)
  // x = J^-1 b, then `refine` steps of iterative refinement with the exact J (each one more
  // sparse product and reduced solve).
  // False if a solve with S failed (PCG: no convergence or S found indefinite).
  bool solve(const double* b, double* x, int refine = 0);
  double factor_nnz() const;
  long iterations() const;  // PCG iterations so far (0 for the direct solver)
  // Setups in which PCG failed and CHOLMOD solved instead ("pcg" only: a failed block-Jacobi
  // factor or a failed solve switches the rest of that setup to a CHOLMOD factor of S).
  long fallbacks() const;
  double analyse_seconds() const;  // CHOLMOD's ordering and symbolic analysis so far
  // Writes S of the current setup and the first right-hand side solved with it to `path`
  // (write_system, sparse_factor.hpp), at the next solve; t is recorded with it.
  void capture_next(const std::string& path, double t);

 private:
  void solve_once(const double* b, double* x);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace isochor
