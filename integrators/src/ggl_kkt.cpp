#include "ggl_kkt.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace isochor {

GglKktSolver::GglKktSolver(const GglForm& form)
    : form_(form),
      n_(form.n()),
      m_(form.m()),
      layout_(form.system().pattern(), form.system().constraint_rows()),
      factor_(layout_, form.system().pattern(), form.system().dofs_per_group(), form.system().constraint_rows()) {
  const auto& rows = form.system().constraint_rows();
  kv_.resize(layout_.p.nnz());
  sx_.resize(form.system().pattern().nnz());
  g_.resize(m_);
  brow_.resize(m_);
  for (Index j = 0; j < m_; ++j) {
    g_[j].resize(rows[j].size());
    brow_[j].resize(rows[j].size());
  }
  gs_.resize(m_, n_);
  k1_.resize(n_ + m_);
  gt_dm_.resize(n_);
  dm_.resize(m_);
  r_.resize(form.size());
  dx_.resize(form.size());
  x_.resize(form.size());
}

GglKktSolver::~GglKktSolver() = default;

double GglKktSolver::factor_entries() const { return factor_.factor_entries(); }

bool GglKktSolver::setup(double cj, const double* values) {
  cj_ = cj;
  values_ = values;
  rho_ = -1;
  direct_ready_ = false;
  const GglForm& f = form_;
  for (std::size_t k = 0; k < f.vq.size(); ++k) sx_[k] = values[f.vq[k]] + cj * values[f.vv[k]];
  const auto& rows = f.system().constraint_rows();
  std::vector<Eigen::Triplet<double>> t;
  for (Index j = 0; j < m_; ++j)
    for (std::size_t k = 0; k < rows[j].size(); ++k) {
      g_[j][k] = values[f.gq[j][k]];
      brow_[j][k] = values[f.gvq[j][k]] + cj * values[f.gvv[j][k]];
      t.emplace_back(j, rows[j][k], g_[j][k]);
    }
  layout_.fill(sx_.data(), g_, brow_, kv_.data());
  if (!factor_.factor(kv_.data())) return false;
  gs_.setFromTriplets(t.begin(), t.end());
  // Analysed afresh each setup: the product's pattern follows G's entries, and G Gᵀ is only
  // m x m with an entry per pair of rows that share a dof.
  ggt_.compute(gs_ * gs_.transpose());
  return ggt_.info() == Eigen::Success;
}

// y += X x for the block of the GGL matrix whose entry k of the system's pattern sits at slot[k].
void GglKktSolver::block_times(const std::vector<Index>& slot, const double* x, double* y) const {
  const SparsePattern& K = form_.system().pattern();
  for (Index c = 0; c < K.n; ++c)
    for (Index k = K.col_ptr[c]; k < K.col_ptr[c + 1]; ++k) y[K.row_ind[k]] += values_[slot[k]] * x[c];
}

void GglKktSolver::precondition(const double* b, double* x) {
  const Index n = n_, m = m_;
  const Eigen::Map<const Eigen::VectorXd> r1(b, n), r2(b + n, n), r3(b + 2 * n, m), r4(b + 2 * n + m, m);
  // K1 [dp; dl] = [r2 + V r1; r4 + G r1].
  k1_.head(n) = r2;
  block_times(form_.vv, r1.data(), k1_.data());
  k1_.tail(m) = r4 + gs_ * r1;
  factor_.solve(k1_.data());
  const auto dp = k1_.head(n);
  // dm = c (G G^T)^-1 (G dp - r3).
  dm_ = cj_ * ggt_.solve(gs_ * dp - r3);
  // dq = dp - G^T dm / c; row 1 exactly: dv = (c I + H_mu) dq + G^T dm - r1.
  gt_dm_ = gs_.transpose() * dm_;
  Eigen::Map<Eigen::VectorXd> dq(x, n), dv(x + n, n);
  dq = dp - gt_dm_ / cj_;
  dv = gt_dm_ - r1;
  block_times(form_.qq, x, x + n);
  std::copy(k1_.data() + n, k1_.data() + n + m, x + 2 * n);
  std::copy(dm_.data(), dm_.data() + m, x + 2 * n + m);
}

bool GglKktSolver::solve(const double* b, double* x, const double* weights) {
  if (!direct_ready_ && refine(b, x, weights)) return true;
  // The refinement did not converge (large steps on stiff contact: K dominates c^2 M): J's own LU
  // for the rest of this setup.
  const SparsePattern& p = form_.pattern();
  if (!direct_ready_) {
    if (!direct_) direct_ = std::make_unique<UmfpackLu>(p.n, p.col_ptr.data(), p.row_ind.data());
    if (!direct_->factor(values_)) return false;
    direct_ready_ = true;
    ++fallbacks_;
  }
  std::copy(b, b + p.n, x);
  direct_->solve(x);
  return std::all_of(x, x + p.n, [](double v) { return std::isfinite(v); });
}

bool GglKktSolver::refine(const double* b, double* x, const double* weights) {
  const SparsePattern& p = form_.pattern();
  const Eigen::Map<const Eigen::VectorXd> w(weights, p.n);
  precondition(b, x_.data());
  // Refinement: each step's change (in the weighted RMS norm) estimates the error before it, and
  // the ratio of two changes the contraction rho; the error after a step is about rho times its
  // change. The first solve of a setup measures rho (two steps at least); the others take the
  // largest rho measured since the setup, times kRhoSafety, for their first step.
  double prev = std::numeric_limits<double>::infinity();
  for (int it = 0; it < kMaxRefinements; ++it) {
    r_ = Eigen::Map<const Eigen::VectorXd>(b, p.n);
    p.add_product(values_, x_.data(), -1.0, r_.data());
    precondition(r_.data(), dx_.data());
    if (!dx_.allFinite()) return false;
    const double change = std::sqrt(dx_.cwiseProduct(w).squaredNorm() / static_cast<double>(p.n));
    x_ += dx_;
    ++refinements_;
    bool done = false;
    if (it == 0) {
      done = rho_ >= 0 && kRhoSafety * rho_ * change <= kRefineTol;
    } else {
      const double rho = change / prev;
      if (rho >= 1 && change > kRefineTol) return false;  // not contracting
      rho_ = std::max(rho_, std::min(rho, 1.0));
      done = std::min(rho, 1.0) * change <= kRefineTol;
    }
    if (done || change == 0) {
      std::copy(x_.data(), x_.data() + p.n, x);
      return true;
    }
    prev = change;
  }
  return false;
}

}  // namespace isochor
