// UMFPACK's sparse LU of one fixed CSC pattern: symbolic analysis once (its own fill-reducing
// order), a numeric factorisation on demand, in-place solves without iterative refinement.
// Multifrontal: dense BLAS kernels on its fronts, which is what a matrix with many dense-ish
// constraint rows needs (KLU's left-looking kernels fill those rows in one by one: 13.5 s
// against 1.45 s on the beam's KKT matrix with 4,600 1-ring rows; docs/decisions.md). Used by
// KktFactor above its row threshold and by IDA's "klu" path on the GGL matrix above it.
#pragma once
#include <cstddef>
#include <vector>

#include "isochor/integrators/sparse_pattern.hpp"

namespace isochor {

// Constraint rows above which the "klu" paths (backward Euler's and statics' KKT matrix, IDA's
// GGL matrix) factor with UMFPACK instead of KLU.
inline constexpr std::size_t kMultifrontalRows = 32;

class UmfpackLu {
 public:
  // The pattern's arrays are read at every factor() and solve(): they must outlive this object.
  UmfpackLu(Index n, const Index* col_ptr, const Index* row_ind);
  ~UmfpackLu();
  UmfpackLu(const UmfpackLu&) = delete;
  UmfpackLu& operator=(const UmfpackLu&) = delete;
  bool factor(const double* values);  // false if singular or out of memory
  void solve(double* rhs) const;      // in place, n entries
  double factor_entries() const;      // entries of L and U of the last factorisation
 private:
  Index n_;
  const Index *col_ptr_, *row_ind_;
  void* symbolic_ = nullptr;
  void* numeric_ = nullptr;
  mutable std::vector<double> b_;  // the right-hand side while UMFPACK solves into rhs
};

}  // namespace isochor
