// A nested-dissection (METIS) ordering for KLU of matrices built on a mesh-like system: the dofs
// come in groups (a node's x, y, z), the matrix has `copies` blocks of n rows that share the
// group graph (IDA's GGL form: q and v; statics: q only), then `tail` rows (multipliers) last.
#pragma once
#include <klu.h>
#include <sunlinsol/sunlinsol_klu.h>

#include <vector>

#include "isochor/integrators/sparse_pattern.hpp"

namespace isochor {

// The old index of each new position: group after group in METIS order, each group's dofs of
// every copy together. The tail holds `tail_blocks` blocks of m multiplier rows (row b m + j
// belongs to constraint j, whose dofs are rows[j]): a local constraint's rows follow the last of
// its groups (so 1-ring zones do not make a dense block), a large one's go last.
std::vector<Index> metis_order(const SparsePattern& K, int per_group, Index n, int copies,
                               const std::vector<std::vector<Index>>& rows, int tail_blocks);

// Makes KLU use `order` (kept alive by the caller) and no block triangular form.
void use_klu_order(SUNLinearSolver klu, const std::vector<Index>* order);
void set_klu_user_order(klu_l_common& common, const std::vector<Index>* order);

}  // namespace isochor
