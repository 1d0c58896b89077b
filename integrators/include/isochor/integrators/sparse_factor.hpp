// Solvers of a symmetric sparse matrix on a fixed pattern (both triangles present), the effective
// stiffness S of the reduced Newton systems:
//  - SymmetricFactor: CHOLMOD (METIS ordering, analysis done once): supernodal Cholesky, and
//    simplicial LDL^T from the first time the matrix is found indefinite (e.g. an unconstrained
//    model under strong compression);
//  - BlockJacobiPcg: preconditioned conjugate gradients with the inverses of the 3x3 nodal
//    diagonal blocks as preconditioner; no factor, memory O(nnz): for meshes beyond a direct
//    factor. Fails (false) when S is found indefinite or the iteration does not converge.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "isochor/integrators/sparse_pattern.hpp"
#include "isochor/integrators/ranks.hpp"

namespace isochor {

class SymmetricSolver {
 public:
  virtual ~SymmetricSolver() = default;
  // Values in the pattern's order. False if the matrix cannot be solved (singular, or indefinite
  // where the method cannot help).
  virtual bool factor(const double* values) = 0;
  // x = S^-1 b; false if the solve failed (no factor, a non-finite solution from a zero pivot;
  // iterative: no convergence or S found indefinite).
  virtual bool solve(const double* b, double* x) = 0;
  virtual double factor_nnz() const = 0;                // entries of the factor (0 for an iterative solver)
  virtual long iterations() const { return 0; }         // iterative: iterations over all solves so far
  virtual double analyse_seconds() const { return 0; }  // direct: ordering and symbolic analysis so far
  // factor() costs no more than a few products (block-Jacobi PCG): worth repeating for a shift.
  virtual bool cheap_factor() const { return false; }
  // factor() again after the entries at pattern positions `changed` (and only those) took new
  // values; an iterative solver updates its copy and preconditioner there only.
  virtual bool refactor(const double* values, const std::vector<Index>& changed) { return factor(values); }
  // solve() from the guess in x (iterative solvers; a direct solver ignores it).
  virtual bool solve_from(const double* b, double* x) { return solve(b, x); }
  // From now on factor() fails on a matrix it finds indefinite instead of factoring it as one: for
  // a minimisation that shifts such a matrix towards definiteness (backward Euler's line search),
  // where an indefinite matrix's Newton direction descends poorly or not at all. Iterative
  // solvers fail there already.
  virtual void refuse_indefinite() {}
  // A direct solver: the floating-point operations of one factorisation and the entries of its
  // factor, from the symbolic analysis (done here if not yet: an ordering, no numbers). False for
  // an iterative solver.
  virtual bool factor_cost(double& flops, double& entries) { return false; }
};

// cholmod: SymmetricFactor; pcg: BlockJacobiPcg with relative residual tolerance `tol` (the GGL
// residual of a reduced solve is ~1e6 times it, so 1e-12 leaves Newton an error of ~1e-6, far
// below its own contraction).
// amg: conjugate gradients preconditioned by one V-cycle of hypre's BoomerAMG (nodal coarsening,
// symmetric Gauss-Seidel), same tolerance; only where isochor was built with hypre
// (amg_available()).
// partition (ranks.hpp, for the system's own pattern): pcg splits its rows over the ranks; the
// others solve the whole matrix on every rank.
enum class SymmetricSolverKind { cholmod, pcg, amg };
std::unique_ptr<SymmetricSolver> make_symmetric_solver(const SparsePattern& pattern, SymmetricSolverKind kind,
                                                       double tol = 1e-12, const DofPartition* partition = nullptr);
bool amg_available();
std::unique_ptr<SymmetricSolver> make_amg_solver(const SparsePattern& pattern, double tol);
// BoomerAMG-preconditioned CG on rows [lo, hi) of S, spread over the ranks of MPI_COMM_WORLD
// (each rank holds its rows; `pattern` and `values` are the whole matrix's, of which a rank reads
// only its columns lo..hi, which are its rows). solve(b, x) reads b and writes x on those rows
// only. One rank and [0, n) is make_amg_solver. Null without hypre. (bench/amg_s.cpp)
std::unique_ptr<SymmetricSolver> make_distributed_amg_solver(const SparsePattern& pattern, Index lo, Index hi,
                                                             double tol);

// A captured system S x = b (ISOCHOR_CAPTURE_S, docs/scenes.md): the pattern, S's values, one
// right-hand side the run solved with it, IDA's c_j and the time. Binary, little-endian:
// "ISOCHORS", int64 n, int64 nnz, double cj, double t, int64 col_ptr[n+1], int64 row_ind[nnz],
// double values[nnz], double b[n]. read_system throws Error naming the file.
struct CapturedSystem {
  SparsePattern pattern;
  std::vector<double> values, b;
  double cj = 0, t = 0;
};
void write_system(const std::string& path, const SparsePattern& pattern, const double* values, const double* b,
                  double cj, double t);
CapturedSystem read_system(const std::string& path);

class SymmetricFactor : public SymmetricSolver {
 public:
  explicit SymmetricFactor(const SparsePattern& pattern);
  ~SymmetricFactor() override;
  bool factor(const double* values) override;
  bool solve(const double* b, double* x) override;
  bool used_ldlt() const;
  void refuse_indefinite() override;
  bool factor_cost(double& flops, double& entries) override;
  double factor_nnz() const override;
  double analyse_seconds() const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace isochor
