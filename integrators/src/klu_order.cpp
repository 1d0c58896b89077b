#include "klu_order.hpp"

#include <klu.h>
#include <metis.h>

#include <algorithm>

namespace isochor {

std::vector<Index> metis_order(const SparsePattern& K, int per_group, Index n, int copies,
                               const std::vector<std::vector<Index>>& rows, int tail_blocks) {
  const Index groups = n / per_group;
  std::vector<std::vector<idx_t>> adj(groups);
  for (Index c = 0; c < n; ++c)
    for (Index k = K.col_ptr[c]; k < K.col_ptr[c + 1]; ++k) {
      const Index a = c / per_group, b = K.row_ind[k] / per_group;
      if (a != b) adj[a].push_back(static_cast<idx_t>(b));
    }
  std::vector<idx_t> xadj{0}, adjncy;
  for (auto& l : adj) {
    std::sort(l.begin(), l.end());
    l.erase(std::unique(l.begin(), l.end()), l.end());
    adjncy.insert(adjncy.end(), l.begin(), l.end());
    xadj.push_back(static_cast<idx_t>(adjncy.size()));
  }
  std::vector<idx_t> perm(groups), iperm(groups);
  for (Index g = 0; g < groups; ++g) perm[g] = static_cast<idx_t>(g);
  idx_t nv = static_cast<idx_t>(groups);
  if (groups > 1 && !adjncy.empty()) {
    idx_t options[METIS_NOPTIONS];
    METIS_SetDefaultOptions(options);
    options[METIS_OPTION_SEED] = 1;
    if (METIS_NodeND(&nv, xadj.data(), adjncy.data(), nullptr, options, perm.data(), iperm.data()) != METIS_OK)
      for (Index g = 0; g < groups; ++g) perm[g] = static_cast<idx_t>(g);
  }
  // KLU wants the old index of each new position. Measured on the coarse ball, METIS_NodeND's
  // perm (not iperm) is that: iperm gave 4x the fill and factorisation time.
  const Index m = static_cast<Index>(rows.size());
  std::vector<Index> position(groups);  // new position of each group
  for (Index k = 0; k < groups; ++k) position[perm[k]] = k;
  constexpr std::size_t kLocal = 64;              // constraints on at most this many groups are local
  std::vector<std::vector<Index>> after(groups);  // constraints placed after each group
  std::vector<Index> last;
  for (Index j = 0; j < m; ++j) {
    Index latest = -1;
    std::size_t count = 0;
    Index previous = -1;
    for (Index d : rows[j])
      if (d / per_group != previous) {
        previous = d / per_group;
        ++count;
        latest = std::max(latest, position[previous]);
      }
    if (count <= kLocal && latest >= 0)
      after[perm[latest]].push_back(j);
    else
      last.push_back(j);
  }
  std::vector<Index> order;
  order.reserve(copies * n + tail_blocks * m);
  auto put_constraint = [&](Index j) {
    for (int b = 0; b < tail_blocks; ++b) order.push_back(copies * n + b * m + j);
  };
  for (Index k = 0; k < groups; ++k) {
    for (int c = 0; c < copies; ++c)
      for (int d = 0; d < per_group; ++d) order.push_back(c * n + perm[k] * per_group + d);
    for (Index j : after[perm[k]]) put_constraint(j);
  }
  for (Index j : last) put_constraint(j);
  return order;
}

namespace {
SuiteSparse_long user_order(SuiteSparse_long n, SuiteSparse_long*, SuiteSparse_long*, SuiteSparse_long* perm,
                            klu_l_common* common) {
  const auto* order = static_cast<const std::vector<Index>*>(common->user_data);
  if (!order || static_cast<SuiteSparse_long>(order->size()) != n) return 0;
  for (SuiteSparse_long k = 0; k < n; ++k) perm[k] = (*order)[k];
  return -1;  // no estimate of nnz(L): KLU sizes L from nnz(A)
}
}  // namespace

void set_klu_user_order(klu_l_common& c, const std::vector<Index>* order) {
  c.ordering = 3;
  c.btf = 0;
  c.user_order = user_order;
  c.user_data = const_cast<std::vector<Index>*>(order);
}

void use_klu_order(SUNLinearSolver klu, const std::vector<Index>* order) {
  set_klu_user_order(*SUNLinSol_KLUGetCommon(klu), order);
}

}  // namespace isochor
