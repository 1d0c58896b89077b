// The KKT matrix [K G^T; G 0] of n dofs and m constraints in one fixed CSC pattern (both
// triangles), with the slot of every entry of K's pattern and of every G entry, and a KLU
// factorisation of it in a METIS order (each local constraint beside its nodes). Used by statics
// (through KINSOL) and by backward Euler when there are many constraints.
#pragma once
#include <klu.h>

#include <memory>
#include <vector>

#include "isochor/integrators/constrained_system.hpp"
#include "isochor/integrators/sparse_pattern.hpp"

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
  void fill(const double* Kvals, const std::vector<std::vector<double>>& G, double* values) const;
};

// KLU on a KktLayout's pattern: symbolic analysis once (METIS order), numeric factorisation on
// demand, in-place solves.
class KktFactor {
 public:
  KktFactor(const KktLayout& layout, const SparsePattern& K, int dofs_per_group,
            const std::vector<std::vector<Index>>& rows);
  ~KktFactor();
  bool factor(const double* values);  // false if singular
  void solve(double* rhs) const;      // in place, n + m
 private:
  const KktLayout& layout_;
  std::vector<Index> order_;
  mutable klu_l_common common_;
  klu_l_symbolic* symbolic_ = nullptr;
  klu_l_numeric* numeric_ = nullptr;
};

}  // namespace isochor
