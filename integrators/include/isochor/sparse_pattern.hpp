// A sparsity pattern in compressed sparse columns (row indices sorted within each column).
#pragma once
#include <algorithm>
#include <cstdint>
#include <vector>

namespace isochor {

using Index = std::int64_t;

struct SparsePattern {
  Index n = 0;  // square n x n
  std::vector<Index> col_ptr, row_ind;
  Index nnz() const { return static_cast<Index>(row_ind.size()); }
  // Position of (row, col) in the value array, or -1 when outside the pattern.
  Index find(Index row, Index col) const {
    auto b = row_ind.begin() + col_ptr[col], e = row_ind.begin() + col_ptr[col + 1];
    auto it = std::lower_bound(b, e, row);
    return (it != e && *it == row) ? static_cast<Index>(it - row_ind.begin()) : -1;
  }
};

}  // namespace isochor
