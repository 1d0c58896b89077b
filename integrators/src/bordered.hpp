// The bordered symmetric system [A G^T; G 0] [x; l] = [r1; r2] of a Newton step with m
// constraints (backward Euler's step matrix, the statics Jacobian), solved through A alone: A by
// a SymmetricSolver (CHOLMOD or block-Jacobi PCG), the borders by the Schur complement
// C = G A^-1 G^T:
//   y = A^-1 r1,   C l = G y - r2,   x = y - Z l   with Z = A^-1 G^T.
// Few constraints (at most kDenseBorderMax, or A solved by an iterative method): C dense, m + 1
// solves with A per setup. Many constraints with CHOLMOD (per-node 1-ring zones, fine patches:
// m comparable to the nodes, where C and Z would be dense m x m and n x m): the sparse border.
// Each local row g_j (on at most kLocalDofs dofs) is added to A as a penalty rho_j g_j g_j^T,
// which leaves the solution unchanged (G x = r2 there), and the Schur complement of
// A_rho = A + G^T D G, D = diag(rho_j), is solved by conjugate gradients preconditioned by D:
//   A_rho x + G^T l = r1 + G^T D r2,   (G A_rho^-1 G^T) l = G A_rho^-1 (r1 + G^T D r2) - r2.
// With every row local, (G A_rho^-1 G^T)^-1 = D + C^-1 (Woodbury): the larger rho, the nearer
// D C_rho is to the identity and the fewer CG iterations (one solve with A_rho's factor each),
// but the worse A_rho's conditioning. rho_j = kRhoScale times A's mean diagonal over the row's
// dofs over |g_j|^2. Measured on a 600-dof chain with 121 rows: scale 1 took 26-44 iterations,
// 100 took 7 with the multipliers within 1e-9 of a dense LU of the KKT matrix, 1000 took 5 but
// lost them to 1e-7; on Cook's membrane with 1-ring zones (N = 24, 30 Newton iterations) 4099,
// 510 and 254 iterations in all. Wide rows (the global zone) keep rho_j = 0 and cost CG a few
// iterations more. The augmented-Lagrangian preconditioner of Fortin and Glowinski (1983) and
// Benzi and Olshanskii (2006).
// Rows on one dof (a support's component, a roller's normal: g_j = c e_i) fix that dof from r2
// alone, x_i = r2_j / c: the sparse border takes such dofs out of A before any of the above (an
// inner BorderedSolver on the other dofs and rows), and finds their multipliers from their own
// row of the first block afterwards. The elimination is exact; it shrinks A (Cook's membrane in
// plane strain by rollers: a third of the dofs) and every other row's clique.
#pragma once
#include <Eigen/Dense>
#include <memory>
#include <string>
#include <vector>

#include "isochor/integrators/sparse_factor.hpp"

namespace isochor {

struct KktLayout;
class KktFactor;

class BorderedSolver {
 public:
  static constexpr Index kDenseBorderMax = 64;  // more constraints: the sparse border (CHOLMOD only)
  static constexpr Index kLocalDofs = 384;      // a row on more dofs stays out of A_rho (its clique)
  static constexpr double kRhoScale = 100;      // rho_j, see above
  static constexpr double kRhoScaleMax = 1e4;   // raised up to this while A_rho is indefinite
  static constexpr double kBorderTol = 1e-10;   // CG's relative residual on the Schur complement
  static constexpr double kResidualMax = 1e-8;  // relative KKT residual above which KLU solves instead
  // CG iterations per pass before KLU solves instead: passes that converged took 10-35 on Cook;
  // the pressure cube with 1-ring zones ran thousands before its fallback.
  static constexpr int kBorderMaxIterations = 200;
  static constexpr int kRefinements = 1;  // passes of iterative refinement after the first

  // A's pattern (both triangles), the dofs of each constraint row, and the solver of A.
  // tol: the relative residual of an iterative solver of A (make_symmetric_solver).
  // partition: A's rows over the ranks (ranks.hpp), for PCG.
  BorderedSolver(const SparsePattern& A, const std::vector<std::vector<Index>>& rows, SymmetricSolverKind kind,
                 double tol = 1e-12, const DofPartition* partition = nullptr);
  // The sparse border whatever m (the inner solver of the dofs that no row pins).
  struct SparseBorder {};
  BorderedSolver(const SparsePattern& A, const std::vector<std::vector<Index>>& rows, SparseBorder);
  ~BorderedSolver();
  bool factor(const double* A_values);  // false: singular, or indefinite for PCG
  // The borders' values (G[j][k] at rows[j][k]): Z and C for the current factor (the sparse
  // border: A_rho from the values factor() kept, factored here). False if a solve or the
  // factorisation failed.
  bool set_borders(const std::vector<std::vector<double>>& G);
  // Solves the bordered system; l has m entries. False if a solve with A failed (the sparse
  // border: or CG on the Schur complement did not converge).
  bool solve(const double* r1, const double* r2, double* x, double* l);
  const SymmetricSolver& symmetric() const;
  SymmetricSolver& symmetric();
  // SymmetricSolver::refuse_indefinite (the sparse border always)
  void refuse_indefinite() { symmetric().refuse_indefinite(); }
  bool sparse_border() const { return sparse_; }
  // Dofs taken out of A by rows on one dof (the sparse border only).
  Index pinned_dofs() const;
  // CG iterations on the Schur complement so far
  long border_iterations() const;
  // Setups the sparse border could not solve (A_rho indefinite at the largest scale, CG on the
  // Schur complement failed, or its answer left a KKT residual above kResidualMax: near-dependent
  // rows) and that KLU on the whole KKT matrix solved; from the first, the rest of the run stays on
  // KLU.
  long kkt_fallbacks() const;

 private:
  struct Pins;
  void init_sparse(const SparsePattern& A);
  bool solve_pinned(const double* r1, const double* r2, double* x, double* l);
  bool set_sparse_borders(const std::vector<std::vector<double>>& G);
  bool solve_sparse(const double* r1, const double* r2, double* x, double* l);
  bool factor_kkt();        // KLU on [A G^T; G 0] with A's values and the borders G_
  bool fall_back_to_kkt();  // from here on KLU
  bool solve_kkt(const Eigen::VectorXd& r1, const Eigen::VectorXd& r2, double* x, double* l);
  bool border_pass(const Eigen::VectorXd& r1, const Eigen::VectorXd& r2, Eigen::VectorXd& x, Eigen::VectorXd& l);
  void apply_G(const Eigen::VectorXd& x, Eigen::VectorXd& y) const;   // y = G x
  void apply_Gt(const Eigen::VectorXd& y, Eigen::VectorXd& x) const;  // x = G^T y

  const std::vector<std::vector<Index>>& rows_;
  Index n_, m_;
  bool sparse_ = false;
  std::unique_ptr<SymmetricSolver> A_;
  // Dense border.
  Eigen::MatrixXd Gt_, Z_;
  Eigen::PartialPivLU<Eigen::MatrixXd> C_;
  // Sparse border: A_rho's pattern is A's and every local row's clique.
  std::vector<Index> a_slot_;                  // A's entry k at A_rho's slot a_slot_[k]
  std::vector<Index> clique_begin_;            // row j's clique slots: clique_[clique_begin_[j] ..]
  std::vector<std::int32_t> clique_;           // slot of (rows[j][a], rows[j][b]), a-major
  std::vector<Index> diag_;                    // A's diagonal slots
  SparsePattern a_pattern_;                    // A's
  std::vector<double> a_values_, rho_values_;  // A's values; A_rho's
  std::vector<std::vector<double>> G_;         // the borders' values
  Eigen::VectorXd rho_;                        // rho_j (0: a wide row)
  double rho_scale_ = kRhoScale;               // the scale of the last factorisation
  std::unique_ptr<KktLayout> kkt_layout_;      // the fallback
  std::unique_ptr<KktFactor> kkt_;
  std::vector<double> kkt_values_;
  bool on_kkt_ = false;
  long kkt_fallbacks_ = 0;
  bool factored_ = false;  // the last setup's factorisation (A_rho's, or the fallback's) succeeded
  long border_iterations_ = 0;
  std::unique_ptr<Pins> pins_;  // rows on one dof, and the solver of the rest
};

// The dofs that rows on one dof pin, and the bordered system of the others: `inner` solves
// [A_FF G_OF^T; G_OF 0] for the free dofs F and the other rows O.
struct BorderedSolver::Pins {
  std::vector<Index> dof, row;           // pinned dof k and the row that pins it
  std::vector<Index> free_dofs;          // F, in order; inner dof -> dof
  std::vector<Index> other_rows;         // O, in order; inner row -> row
  std::vector<std::vector<Index>> rows;  // O's rows on F, in inner numbering (inner keeps a reference)
  std::vector<std::vector<Index>> kept;  // rows[o][k] is entry kept[o][k] of row other_rows[o]
  std::vector<Index> a_free;             // A_FF's entry k is A's entry a_free[k]
  std::vector<double> a_values;          // A_FF's values
  std::vector<std::vector<double>> G;    // O's values on F
  SparsePattern pattern;                 // A_FF's
  std::unique_ptr<BorderedSolver> inner;
  Pins(const SparsePattern& A, const std::vector<std::vector<Index>>& all_rows, std::vector<Index> pinned_dof,
       std::vector<Index> pinned_row);
};

inline const SymmetricSolver& BorderedSolver::symmetric() const { return pins_ ? pins_->inner->symmetric() : *A_; }
inline SymmetricSolver& BorderedSolver::symmetric() { return pins_ ? pins_->inner->symmetric() : *A_; }
inline Index BorderedSolver::pinned_dofs() const { return pins_ ? static_cast<Index>(pins_->dof.size()) : 0; }
inline long BorderedSolver::border_iterations() const {
  return pins_ ? pins_->inner->border_iterations() : border_iterations_;
}
inline long BorderedSolver::kkt_fallbacks() const { return pins_ ? pins_->inner->kkt_fallbacks() : kkt_fallbacks_; }

}  // namespace isochor
