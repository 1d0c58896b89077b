// A sparsity pattern in compressed sparse columns (row indices sorted within each column).
#pragma once
#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

namespace isochor {

using Index = std::int64_t;

struct SparsePattern {
  Index n = 0;  // square n x n
  std::vector<Index> col_ptr, row_ind;
  Index nnz() const { return static_cast<Index>(row_ind.size()); }
  // The pattern of n x n entries given as (column, row) pairs, in any order, repeats allowed.
  static SparsePattern from_entries(Index n, std::vector<std::pair<Index, Index>> entries) {
    std::sort(entries.begin(), entries.end());
    entries.erase(std::unique(entries.begin(), entries.end()), entries.end());
    SparsePattern p;
    p.n = n;
    p.col_ptr.assign(n + 1, 0);
    p.row_ind.resize(entries.size());
    for (std::size_t k = 0; k < entries.size(); ++k) {
      p.col_ptr[entries[k].first + 1]++;
      p.row_ind[k] = entries[k].second;
    }
    for (Index c = 0; c < n; ++c) p.col_ptr[c + 1] += p.col_ptr[c];
    return p;
  }
  // y += scale A x for values A in this pattern (n entries each).
  void add_product(const double* values, const double* x, double scale, double* y) const {
    for (Index c = 0; c < n; ++c)
      for (Index k = col_ptr[c]; k < col_ptr[c + 1]; ++k) y[row_ind[k]] += scale * values[k] * x[c];
  }
  // Position of (row, col) in the value array, or -1 when outside the pattern.
  Index find(Index row, Index col) const {
    auto b = row_ind.begin() + col_ptr[col], e = row_ind.begin() + col_ptr[col + 1];
    auto it = std::lower_bound(b, e, row);
    return (it != e && *it == row) ? static_cast<Index>(it - row_ind.begin()) : -1;
  }
};

}  // namespace isochor
