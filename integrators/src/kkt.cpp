#include "kkt.hpp"

#include <algorithm>

#include "klu_order.hpp"

namespace isochor {

void add_constraint_terms(ConstrainedSystem& sys, double t, const VectorXd& q, const VectorXd& lambda,
                          std::vector<std::vector<double>>& G, VectorXd& g, double* r) {
  if (sys.num_constraints() == 0) return;
  sys.constraint(t, q, g);
  sys.constraint_jacobian(t, q, G, nullptr);
  const auto& rows = sys.constraint_rows();
  for (std::size_t j = 0; j < G.size(); ++j)
    for (std::size_t k = 0; k < G[j].size(); ++k) r[rows[j][k]] += G[j][k] * lambda[static_cast<Index>(j)];
}

KktLayout::KktLayout(const SparsePattern& K, const std::vector<std::vector<Index>>& rows) {
  const Index n = K.n, m = static_cast<Index>(rows.size());
  std::vector<std::pair<Index, Index>> e;  // (col, row)
  for (Index c = 0; c < n; ++c)
    for (Index k = K.col_ptr[c]; k < K.col_ptr[c + 1]; ++k) e.emplace_back(c, K.row_ind[k]);
  for (Index j = 0; j < m; ++j)
    for (Index d : rows[j]) {
      e.emplace_back(n + j, d);
      e.emplace_back(d, n + j);
    }
  p = SparsePattern::from_entries(n + m, std::move(e));
  kk.resize(K.nnz());
  for (Index c = 0; c < n; ++c)
    for (Index k = K.col_ptr[c]; k < K.col_ptr[c + 1]; ++k) kk[k] = p.find(K.row_ind[k], c);
  gcol.resize(m);
  grow.resize(m);
  for (Index j = 0; j < m; ++j)
    for (Index d : rows[j]) {
      gcol[j].push_back(p.find(d, n + j));
      grow[j].push_back(p.find(n + j, d));
    }
}

void KktLayout::fill(const double* Kvals, const std::vector<std::vector<double>>& C,
                     const std::vector<std::vector<double>>& R, double* values) const {
  std::fill(values, values + p.nnz(), 0.0);
  for (std::size_t k = 0; k < kk.size(); ++k) values[kk[k]] += Kvals[k];
  for (std::size_t j = 0; j < C.size(); ++j)
    for (std::size_t k = 0; k < C[j].size(); ++k) {
      values[gcol[j][k]] += C[j][k];
      values[grow[j][k]] += R[j][k];
    }
}

KktFactor::KktFactor(const KktLayout& layout, const SparsePattern& K, int dofs_per_group,
                     const std::vector<std::vector<Index>>& rows)
    : layout_(layout) {
  if (rows.size() > kMultifrontalRows) {
    umfpack_ = std::make_unique<UmfpackLu>(layout_.p.n, layout_.p.col_ptr.data(), layout_.p.row_ind.data());
    return;
  }
  order_ = metis_order(K, dofs_per_group, K.n, 1, rows, 1);
  klu_l_defaults(&common_);
  set_klu_user_order(common_, &order_);
  symbolic_ = klu_l_analyze(layout_.p.n, const_cast<Index*>(layout_.p.col_ptr.data()),
                            const_cast<Index*>(layout_.p.row_ind.data()), &common_);
}

KktFactor::~KktFactor() {
  if (numeric_) klu_l_free_numeric(&numeric_, &common_);
  if (symbolic_) klu_l_free_symbolic(&symbolic_, &common_);
}

bool KktFactor::factor(const double* values) {
  if (umfpack_) return umfpack_->factor(values);
  if (!symbolic_) return false;
  if (numeric_) klu_l_free_numeric(&numeric_, &common_);
  numeric_ = klu_l_factor(const_cast<Index*>(layout_.p.col_ptr.data()), const_cast<Index*>(layout_.p.row_ind.data()),
                          const_cast<double*>(values), symbolic_, &common_);
  return numeric_ && common_.status == KLU_OK;
}

double KktFactor::factor_entries() const {
  if (umfpack_) return umfpack_->factor_entries();
  return numeric_ ? static_cast<double>(numeric_->lnz + numeric_->unz) : 0.0;
}

void KktFactor::solve(double* rhs) const {
  if (umfpack_)
    umfpack_->solve(rhs);
  else
    klu_l_solve(symbolic_, numeric_, layout_.p.n, 1, rhs, &common_);
}

}  // namespace isochor
