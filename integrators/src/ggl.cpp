#include "isochor/integrators/ggl.hpp"

#include <algorithm>
#include <cmath>

namespace isochor {

GglForm::GglForm(ConstrainedSystem& sys) : sys_(sys), n_(sys.num_dofs()), m_(sys.num_constraints()) {
  const SparsePattern& K = sys.pattern();
  const auto& rows = sys.constraint_rows();
  const Index n = n_, m = m_, N = size();
  std::vector<std::pair<Index, Index>> e;  // (col, row)
  e.reserve(3 * K.nnz() + n);
  for (Index c = 0; c < n; ++c)
    for (Index k = K.col_ptr[c]; k < K.col_ptr[c + 1]; ++k) {
      const Index r = K.row_ind[k];
      e.emplace_back(c, r);
      e.emplace_back(c, n + r);
      e.emplace_back(n + c, n + r);
    }
  for (Index i = 0; i < n; ++i) e.emplace_back(n + i, i);
  for (Index j = 0; j < m; ++j)
    for (Index d : rows[j]) {
      e.emplace_back(d, 2 * n + j);          // G in F_g
      e.emplace_back(d, 2 * n + m + j);      // d(G v)/dq in F_gv
      e.emplace_back(n + d, 2 * n + m + j);  // G in F_gv
      e.emplace_back(2 * n + m + j, d);      // G^T mu in F_q
      e.emplace_back(2 * n + j, n + d);      // G^T lambda in F_v
    }
  p_ = SparsePattern::from_entries(N, std::move(e));
  qq.resize(K.nnz());
  vq.resize(K.nnz());
  vv.resize(K.nnz());
  for (Index c = 0; c < n; ++c)
    for (Index k = K.col_ptr[c]; k < K.col_ptr[c + 1]; ++k) {
      const Index r = K.row_ind[k];
      qq[k] = p_.find(r, c);
      vq[k] = p_.find(n + r, c);
      vv[k] = p_.find(n + r, n + c);
    }
  q_diag.resize(n);
  v_diag.resize(n);
  qv.resize(n);
  for (Index i = 0; i < n; ++i) {
    q_diag[i] = p_.find(i, i);
    v_diag[i] = p_.find(n + i, n + i);
    qv[i] = p_.find(i, n + i);
  }
  auto per_row = [&](std::vector<std::vector<Index>>& out, Index row0, Index col0, bool transpose) {
    out.assign(m, {});
    for (Index j = 0; j < m; ++j)
      for (Index d : rows[j]) out[j].push_back(transpose ? p_.find(col0 + d, row0 + j) : p_.find(row0 + j, col0 + d));
  };
  per_row(gq, 2 * n, 0, false);
  per_row(gvq, 2 * n + m, 0, false);
  per_row(gvv, 2 * n + m, n, false);
  per_row(qmu, 2 * n + m, 0, true);
  per_row(vlam, 2 * n, n, true);

  q_.resize(n), v_.resize(n), qd_.resize(n), vd_.resize(n), lambda_.resize(m), mu_.resize(m), f_.resize(n),
      g_.resize(m), gt_.resize(m);
  sA_.resize(K.nnz());
  sB_.resize(K.nnz());
  sC_.resize(K.nnz());
  G_.resize(m);
  Gv_.resize(m);
  for (Index j = 0; j < m; ++j) {
    G_[j].resize(rows[j].size());
    Gv_[j].resize(rows[j].size());
  }
}

void GglForm::unpack(const double* y, const double* yp) {
  q_ = Eigen::Map<const VectorXd>(y, n_);
  v_ = Eigen::Map<const VectorXd>(y + n_, n_);
  lambda_ = Eigen::Map<const VectorXd>(y + 2 * n_, m_);
  mu_ = Eigen::Map<const VectorXd>(y + 2 * n_ + m_, m_);
  qd_ = Eigen::Map<const VectorXd>(yp, n_);
  vd_ = Eigen::Map<const VectorXd>(yp + n_, n_);
}

bool GglForm::residual(double t, const double* y, const double* yp, double* r) {
  unpack(y, yp);
  const Index n = n_, m = m_;
  sys_.force(t, q_, v_, f_);
  sys_.constraint(t, q_, g_);
  sys_.constraint_jacobian(t, q_, G_, &gt_);
  Eigen::Map<VectorXd> Fq(r, n), Fv(r + n, n), Fg(r + 2 * n, m), Fgv(r + 2 * n + m, m);
  Fq = qd_ - v_;
  Fv = sys_.mass().cwiseProduct(vd_) - f_;
  Fg = g_;
  for (Index j = 0; j < m; ++j) {
    const auto& rows = sys_.constraint_rows()[j];
    double gv = 0;
    for (std::size_t k = 0; k < rows.size(); ++k) {
      Fq[rows[k]] += G_[j][k] * mu_[j];
      Fv[rows[k]] += G_[j][k] * lambda_[j];
      gv += G_[j][k] * v_[rows[k]];
    }
    Fgv[j] = gv + gt_[j];
  }
  for (Index i = 0; i < size(); ++i)
    if (!std::isfinite(r[i])) return false;
  return true;
}

void GglForm::shift_cj(double d, double* val) const {
  const VectorXd& M = sys_.mass();
  for (Index i = 0; i < n_; ++i) {
    val[q_diag[i]] += d;
    val[v_diag[i]] += d * M[i];
  }
}

void GglForm::jacobian(double t, double cj, const double* y, const double* yp, double* val) {
  unpack(y, yp);
  const Index n = n_, m = m_;
  std::fill(val, val + p_.nnz(), 0.0);
  std::fill(sA_.begin(), sA_.end(), 0.0);
  std::fill(sB_.begin(), sB_.end(), 0.0);
  std::fill(sC_.begin(), sC_.end(), 0.0);
  if (m) {
    sys_.add_constraint_hessian(t, q_, mu_, 1.0, sA_.data());
    sys_.add_constraint_hessian(t, q_, lambda_, 1.0, sB_.data());
  }
  sys_.add_force_jacobians(t, q_, v_, sB_.data(), sC_.data());
  for (std::size_t k = 0; k < sA_.size(); ++k) {
    val[qq[k]] += sA_[k];
    val[vq[k]] += sB_[k];
    val[vv[k]] += sC_[k];
  }
  shift_cj(cj, val);
  for (Index i = 0; i < n; ++i) val[qv[i]] = -1.0;
  if (m) {
    sys_.constraint_jacobian(t, q_, G_, nullptr);
    sys_.constraint_velocity_jacobian(t, q_, v_, Gv_);
    for (Index j = 0; j < m; ++j)
      for (std::size_t k = 0; k < G_[j].size(); ++k) {
        val[gq[j][k]] += G_[j][k];
        val[gvv[j][k]] += G_[j][k];
        val[qmu[j][k]] += G_[j][k];
        val[vlam[j][k]] += G_[j][k];
        val[gvq[j][k]] += Gv_[j][k];
      }
  }
}

}  // namespace isochor
