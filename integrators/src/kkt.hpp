// The KKT matrix [K G^T; G 0] of n dofs and m constraints in one fixed CSC pattern (both
// triangles), with the slot of every entry of K's pattern and of every G entry, and its sparse LU
// (KktFactor: KLU, or UMFPACK for many rows). Used by statics (through KINSOL), by backward
// Euler when there are many constraints, and by IDA's GGL system with many (ggl_kkt.hpp).
#pragma once
#include <klu.h>

#include <cstddef>
#include <memory>
#include <vector>

#include "isochor/integrators/constrained_system.hpp"
#include "isochor/integrators/sparse_pattern.hpp"
#include "umfpack_lu.hpp"

namespace isochor {

// The constraint part of a KKT residual at (q, lambda): g = g(q, t), G = dg/dq (rows of the
// system's constraint_rows()), and r += G^T lambda. r holds n entries.
void add_constraint_terms(ConstrainedSystem& sys, double t, const VectorXd& q, const VectorXd& lambda,
                          std::vector<std::vector<double>>& G, VectorXd& g, double* r);

struct KktLayout {
  SparsePattern p;                             // (n + m) x (n + m)
  std::vector<Index> kk;                       // slot of each entry of the n x n pattern
  std::vector<std::vector<Index>> gcol, grow;  // slots of G^T (column n + j) and G (row n + j)
  KktLayout(const SparsePattern& K, const std::vector<std::vector<Index>>& rows);
  // values (p.nnz()) = [Kvals G^T; G 0].
  void fill(const double* Kvals, const std::vector<std::vector<double>>& G, double* values) const {
    fill(Kvals, G, G, values);
  }
  // values = [Kvals C^T; R 0]: another matrix than G in the bottom rows, on G's pattern.
  void fill(const double* Kvals, const std::vector<std::vector<double>>& C, const std::vector<std::vector<double>>& R,
            double* values) const;
};

// A sparse LU of a KktLayout's pattern: symbolic analysis once, numeric factorisation on demand,
// in-place solves. Up to kMultifrontalRows constraint rows, KLU in a METIS order (each local
// constraint beside its nodes); above, UMFPACK (multifrontal, dense BLAS kernels on its fronts,
// its own fill-reducing order). Measured on the clamped beam with 4,600 1-ring zones (21,870
// tets, 18,400 unknowns; backward Euler, 50 steps, one factorisation, one thread): KLU in the
// METIS order 13.5 s to factor, 21 s the run; KLU in its own AMD order 235 s; UMFPACK 1.45 s
// (9.2M + 9.6M factor entries), 7.9 s the run, with the same 139 Newton iterations; with 108
// 2-ring patches 5.23 s against 0.79 s for two factorisations (docs/decisions.md). 32 is where
// backward Euler leaves its dense border for this matrix.
class KktFactor {
 public:
  static constexpr std::size_t kMultifrontalRows = isochor::kMultifrontalRows;
  KktFactor(const KktLayout& layout, const SparsePattern& K, int dofs_per_group,
            const std::vector<std::vector<Index>>& rows);
  ~KktFactor();
  bool factor(const double* values);  // false if singular
  void solve(double* rhs) const;      // in place, n + m
  double factor_entries() const;      // entries of L and U of the last factorisation
 private:
  const KktLayout& layout_;
  std::vector<Index> order_;
  mutable klu_l_common common_;
  klu_l_symbolic* symbolic_ = nullptr;
  klu_l_numeric* numeric_ = nullptr;
  std::unique_ptr<UmfpackLu> umfpack_;  // above kMultifrontalRows, instead of KLU
};

}  // namespace isochor
