// The bordered symmetric system [A G^T; G 0] [x; l] = [r1; r2] of a Newton step with m
// constraints (backward Euler's step matrix, the statics Jacobian), solved through A alone: A by
// a SymmetricSolver (CHOLMOD or block-Jacobi PCG), the borders by the dense m x m Schur
// complement C = G A^-1 G^T:
//   y = A^-1 r1,   C l = G y - r2,   x = y - Z l   with Z = A^-1 G^T.
// For a few constraints (zones): m + 1 solves with A per setup instead of a factorisation of the
// whole (n + m) matrix.
#pragma once
#include <Eigen/Dense>
#include <memory>
#include <string>
#include <vector>

#include "isochor/integrators/sparse_factor.hpp"

namespace isochor {

class BorderedSolver {
 public:
  // A's pattern (both triangles), the dofs of each constraint row, and the solver of A.
  // tol: the relative residual of an iterative solver of A (make_symmetric_solver).
  BorderedSolver(const SparsePattern& A, const std::vector<std::vector<Index>>& rows, SymmetricSolverKind kind,
                 double tol = 1e-12);
  bool factor(const double* A_values);  // false: singular, or indefinite for PCG
  // The borders' values (G[j][k] at rows[j][k]): Z and C for the current factor. False if a
  // solve failed.
  bool set_borders(const std::vector<std::vector<double>>& G);
  // Solves the bordered system; l has m entries. False if a solve with A failed.
  bool solve(const double* r1, const double* r2, double* x, double* l);
  const SymmetricSolver& symmetric() const { return *A_; }
  SymmetricSolver& symmetric() { return *A_; }
  void refuse_indefinite() { A_->refuse_indefinite(); }  // SymmetricSolver::refuse_indefinite

 private:
  const std::vector<std::vector<Index>>& rows_;
  Index n_, m_;
  std::unique_ptr<SymmetricSolver> A_;
  Eigen::MatrixXd Gt_, Z_;
  Eigen::PartialPivLU<Eigen::MatrixXd> C_;
};

}  // namespace isochor
