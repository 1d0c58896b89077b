// A symmetric sparse matrix on a fixed pattern, factored by CHOLMOD (METIS ordering, analysis
// done once): supernodal Cholesky, and simplicial LDL^T from the first time the matrix is found
// indefinite (e.g. an unconstrained model under strong compression).
#pragma once
#include <memory>

#include "isochor/sparse_pattern.hpp"

namespace isochor {

class SymmetricFactor {
 public:
  explicit SymmetricFactor(const SparsePattern& pattern);
  ~SymmetricFactor();
  // Values in the pattern's order (both triangles present; the lower one is used). False if the
  // matrix is singular (or indefinite where LDL^T cannot help).
  bool factor(const double* values);
  void solve(const double* b, double* x);
  bool used_ldlt() const;
  double factor_nnz() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace isochor
