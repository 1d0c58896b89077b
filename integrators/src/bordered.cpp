#include "bordered.hpp"

#include "kkt.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "isochor/base/error.hpp"

namespace isochor {

namespace {
// A_rho's pattern: A's entries and the clique of every local row.
SparsePattern augmented_pattern(const SparsePattern& A, const std::vector<std::vector<Index>>& rows,
                                const std::vector<char>& local) {
  std::vector<std::pair<Index, Index>> entries;
  entries.reserve(A.nnz());
  for (Index c = 0; c < A.n; ++c)
    for (Index k = A.col_ptr[c]; k < A.col_ptr[c + 1]; ++k) entries.emplace_back(c, A.row_ind[k]);
  for (std::size_t j = 0; j < rows.size(); ++j)
    if (local[j])
      for (Index a : rows[j])
        for (Index b : rows[j]) entries.emplace_back(a, b);
  return SparsePattern::from_entries(A.n, std::move(entries));
}
}  // namespace

BorderedSolver::BorderedSolver(const SparsePattern& A, const std::vector<std::vector<Index>>& rows,
                               SymmetricSolverKind kind, double tol, const DofPartition* partition)
    : rows_(rows),
      n_(A.n),
      m_(static_cast<Index>(rows.size())),
      sparse_(kind == SymmetricSolverKind::cholmod && m_ > kDenseBorderMax) {
  if (!sparse_) {
    A_ = make_symmetric_solver(A, kind, tol, partition);
    Gt_.setZero(n_, m_);
    Z_.setZero(n_, m_);
    return;
  }
  // A dof that exactly one row on one dof names is pinned (two such rows on a dof stay rows: the
  // KKT matrix is singular there, and the solver says so as before).
  std::vector<int> single(n_, 0);
  for (const std::vector<Index>& r : rows)
    if (r.size() == 1) single[r[0]]++;
  std::vector<Index> dofs, pin_rows;
  for (Index j = 0; j < m_; ++j)
    if (rows[j].size() == 1 && single[rows[j][0]] == 1) {
      dofs.push_back(rows[j][0]);
      pin_rows.push_back(j);
    }
  if (dofs.empty()) {
    init_sparse(A);
    return;
  }
  pins_ = std::make_unique<Pins>(A, rows, std::move(dofs), std::move(pin_rows));
  a_pattern_ = A;
  a_values_.resize(A.nnz());
}

BorderedSolver::BorderedSolver(const SparsePattern& A, const std::vector<std::vector<Index>>& rows, SparseBorder)
    : rows_(rows), n_(A.n), m_(static_cast<Index>(rows.size())), sparse_(true) {
  init_sparse(A);
}

BorderedSolver::Pins::Pins(const SparsePattern& A, const std::vector<std::vector<Index>>& all_rows,
                           std::vector<Index> pinned_dof, std::vector<Index> pinned_row)
    : dof(std::move(pinned_dof)), row(std::move(pinned_row)) {
  std::vector<Index> inner_of(A.n, 0);
  for (Index d : dof) inner_of[d] = -1;
  for (Index i = 0; i < A.n; ++i)
    if (inner_of[i] == 0) {
      inner_of[i] = static_cast<Index>(free_dofs.size());
      free_dofs.push_back(i);
    }
  std::vector<char> pins_it(all_rows.size(), 0);
  for (Index j : row) pins_it[j] = 1;
  for (std::size_t j = 0; j < all_rows.size(); ++j) {
    if (pins_it[j]) continue;
    other_rows.push_back(static_cast<Index>(j));
    rows.emplace_back();
    kept.emplace_back();
    for (std::size_t k = 0; k < all_rows[j].size(); ++k)
      if (inner_of[all_rows[j][k]] >= 0) {
        rows.back().push_back(inner_of[all_rows[j][k]]);
        kept.back().push_back(static_cast<Index>(k));
      }
    G.emplace_back(rows.back().size());
  }
  std::vector<std::pair<Index, Index>> entries;
  for (Index c : free_dofs)
    for (Index k = A.col_ptr[c]; k < A.col_ptr[c + 1]; ++k)
      if (inner_of[A.row_ind[k]] >= 0) entries.emplace_back(inner_of[c], inner_of[A.row_ind[k]]);
  pattern = SparsePattern::from_entries(static_cast<Index>(free_dofs.size()), std::move(entries));
  a_free.resize(pattern.nnz());
  a_values.resize(pattern.nnz());
  for (Index c = 0; c < pattern.n; ++c)
    for (Index k = pattern.col_ptr[c]; k < pattern.col_ptr[c + 1]; ++k)
      a_free[k] = A.find(free_dofs[pattern.row_ind[k]], free_dofs[c]);
  inner = std::make_unique<BorderedSolver>(pattern, rows, SparseBorder{});
}

void BorderedSolver::init_sparse(const SparsePattern& A) {
  std::vector<char> local(m_);
  for (Index j = 0; j < m_; ++j) local[j] = static_cast<Index>(rows_[j].size()) <= kLocalDofs;
  const SparsePattern P = augmented_pattern(A, rows_, local);
  if (P.nnz() > std::numeric_limits<std::int32_t>::max())  // the clique slots are 32-bit
    throw Error("the sparse border's matrix has " + std::to_string(P.nnz()) +
                " entries, more than 2^31: use integrator.linear_solver = \"klu\"");
  A_ = make_symmetric_solver(P, SymmetricSolverKind::cholmod);
  A_->refuse_indefinite();  // set_sparse_borders raises rho instead
  a_slot_.resize(A.nnz());
  for (Index c = 0; c < n_; ++c)
    for (Index k = A.col_ptr[c]; k < A.col_ptr[c + 1]; ++k) a_slot_[k] = P.find(A.row_ind[k], c);
  clique_begin_.assign(m_ + 1, 0);
  for (Index j = 0; j < m_; ++j) {
    const Index d = local[j] ? static_cast<Index>(rows_[j].size()) : 0;
    clique_begin_[j + 1] = clique_begin_[j] + d * d;
  }
  clique_.resize(clique_begin_[m_]);
  for (Index j = 0; j < m_; ++j) {
    if (!local[j]) continue;
    std::int32_t* s = clique_.data() + clique_begin_[j];
    for (Index a : rows_[j])
      for (Index b : rows_[j]) *s++ = static_cast<std::int32_t>(P.find(b, a));
  }
  diag_.resize(n_);
  for (Index i = 0; i < n_; ++i) diag_[i] = A.find(i, i);
  a_pattern_ = A;
  a_values_.resize(A.nnz());
  rho_values_.resize(P.nnz());
  rho_.setZero(m_);
}

BorderedSolver::~BorderedSolver() = default;

bool BorderedSolver::factor(const double* A_values) {
  if (!sparse_) return A_->factor(A_values);
  std::copy(A_values, A_values + a_values_.size(), a_values_.begin());  // factored with the borders
  if (!pins_) return true;
  for (std::size_t k = 0; k < pins_->a_free.size(); ++k) pins_->a_values[k] = A_values[pins_->a_free[k]];
  return pins_->inner->factor(pins_->a_values.data());
}

bool BorderedSolver::set_borders(const std::vector<std::vector<double>>& G) {
  if (m_ == 0 && !sparse_) return true;  // the sparse border factors A_rho here
  if (pins_) {
    G_ = G;
    for (Index j : pins_->row)
      if (!(G[j][0] != 0.0 && std::isfinite(G[j][0]))) return false;  // no dof pinned by it
    for (std::size_t o = 0; o < pins_->other_rows.size(); ++o)
      for (std::size_t k = 0; k < pins_->kept[o].size(); ++k)
        pins_->G[o][k] = G[pins_->other_rows[o]][pins_->kept[o][k]];
    return pins_->inner->set_borders(pins_->G);
  }
  if (sparse_) return set_sparse_borders(G);
  Gt_.setZero();
  for (Index j = 0; j < m_; ++j)
    for (std::size_t k = 0; k < G[j].size(); ++k) Gt_(rows_[j][k], j) = G[j][k];
  bool ok = true;
  for (Index j = 0; j < m_; ++j) ok = A_->solve(Gt_.col(j).data(), Z_.col(j).data()) && ok;
  C_.compute(Gt_.transpose() * Z_);
  return ok;
}

// rho_j = scale x |A's diagonal| over row j's dofs (mean) / |g_j|^2: the row's penalty as stiff
// as the nodes it moves. A_rho must be positive definite for CG on its Schur complement (an
// indefinite LDL^T made CG diverge on a cantilever with 1-ring zones, whose A = K + sum lambda H
// is indefinite across the rows): where CHOLMOD finds it is not, the scale grows tenfold, up to
// kRhoScaleMax (A positive definite on the rows' null space makes A_rho so for a large enough
// scale). The next setup starts a tenth of the way back.
bool BorderedSolver::factor_kkt() {
  if (!kkt_) {
    kkt_layout_ = std::make_unique<KktLayout>(a_pattern_, rows_);
    kkt_ = std::make_unique<KktFactor>(*kkt_layout_, a_pattern_, n_ % 3 == 0 ? 3 : 1, rows_);
    kkt_values_.resize(kkt_layout_->p.nnz());
  }
  kkt_layout_->fill(a_values_.data(), G_, kkt_values_.data());
  return kkt_->factor(kkt_values_.data());
}

bool BorderedSolver::fall_back_to_kkt() {
  on_kkt_ = true;
  ++kkt_fallbacks_;
  factored_ = factor_kkt();
  return factored_;
}

// KLU on this setup's KKT matrix (factored here on the first fallback).
bool BorderedSolver::solve_kkt(const Eigen::VectorXd& r1, const Eigen::VectorXd& r2, double* x, double* l) {
  if (!on_kkt_ && !fall_back_to_kkt()) return false;
  if (!factored_) return false;
  Eigen::VectorXd rhs(n_ + m_);
  rhs << r1, r2;
  kkt_->solve(rhs.data());
  Eigen::Map<Eigen::VectorXd>(x, n_) = rhs.head(n_);
  Eigen::Map<Eigen::VectorXd>(l, m_) = rhs.tail(m_);
  return rhs.allFinite();
}

bool BorderedSolver::set_sparse_borders(const std::vector<std::vector<double>>& G) {
  G_ = G;
  if (on_kkt_) return factored_ = factor_kkt();
  double mean_diag = 0;
  for (Index i = 0; i < n_; ++i) mean_diag += diag_[i] >= 0 ? std::abs(a_values_[diag_[i]]) : 0.0;
  mean_diag /= std::max<Index>(n_, 1);
  std::vector<double> unit(m_, 0.0);  // rho_j at scale 1
  for (Index j = 0; j < m_; ++j) {
    const Index d = static_cast<Index>(rows_[j].size());
    if (clique_begin_[j + 1] == clique_begin_[j] || d == 0) continue;
    double g2 = 0, a = 0;
    for (Index k = 0; k < d; ++k) {
      g2 += G[j][k] * G[j][k];
      const Index s = diag_[rows_[j][k]];
      a += s >= 0 ? std::abs(a_values_[s]) : 0.0;
    }
    a = a > 0 ? a / d : mean_diag;
    if (g2 > 0 && a > 0) unit[j] = a / g2;
  }
  for (rho_scale_ = std::max(kRhoScale, rho_scale_ / 10); rho_scale_ <= kRhoScaleMax; rho_scale_ *= 10) {
    std::fill(rho_values_.begin(), rho_values_.end(), 0.0);
    for (std::size_t k = 0; k < a_values_.size(); ++k) rho_values_[a_slot_[k]] += a_values_[k];
    for (Index j = 0; j < m_; ++j) {
      rho_[j] = rho_scale_ * unit[j];
      if (rho_[j] == 0) continue;
      const Index d = static_cast<Index>(rows_[j].size());
      const std::int32_t* s = clique_.data() + clique_begin_[j];
      for (Index p = 0; p < d; ++p)
        for (Index q = 0; q < d; ++q) rho_values_[*s++] += rho_[j] * G[j][p] * G[j][q];
    }
    factored_ = A_->factor(rho_values_.data());
    if (factored_) return true;
  }
  rho_scale_ = kRhoScaleMax;
  return fall_back_to_kkt();
}

void BorderedSolver::apply_G(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
  y.resize(m_);
  for (Index j = 0; j < m_; ++j) {
    double s = 0;
    for (std::size_t k = 0; k < G_[j].size(); ++k) s += G_[j][k] * x[rows_[j][k]];
    y[j] = s;
  }
}

void BorderedSolver::apply_Gt(const Eigen::VectorXd& y, Eigen::VectorXd& x) const {
  x.setZero(n_);
  for (Index j = 0; j < m_; ++j)
    for (std::size_t k = 0; k < G_[j].size(); ++k) x[rows_[j][k]] += G_[j][k] * y[j];
}

bool BorderedSolver::solve(const double* r1, const double* r2, double* x, double* l) {
  if (pins_) return solve_pinned(r1, r2, x, l);
  if (sparse_) return solve_sparse(r1, r2, x, l);
  Eigen::Map<Eigen::VectorXd> y(x, n_);
  const bool ok = A_->solve(r1, x);
  if (m_ == 0) return ok;
  Eigen::Map<Eigen::VectorXd> dl(l, m_);
  dl = C_.solve(Gt_.transpose() * y - Eigen::Map<const Eigen::VectorXd>(r2, m_));
  y -= Z_ * dl;
  return ok;
}

// One pass: preconditioned CG on C_rho l = G A_rho^-1 (r1 + G^T D r2) - r2, with u = A_rho^-1 G^T l
// kept along (each iteration's solve gives A_rho^-1 G^T p), so that x = w - u needs no further
// solve.
bool BorderedSolver::border_pass(const Eigen::VectorXd& r1, const Eigen::VectorXd& r2, Eigen::VectorXd& x,
                                 Eigen::VectorXd& L) {
  Eigen::VectorXd t, w(n_), s(n_);
  apply_Gt(rho_.cwiseProduct(r2), t);
  t += r1;
  bool ok = A_->solve(t.data(), w.data());
  Eigen::VectorXd b, r, z, p, q, u = Eigen::VectorXd::Zero(n_);
  apply_G(w, b);
  b -= r2;
  L.setZero(m_);
  r = b;
  auto precondition = [&](const Eigen::VectorXd& v, Eigen::VectorXd& out) {
    out.resize(m_);
    for (Index j = 0; j < m_; ++j) out[j] = rho_[j] > 0 ? rho_[j] * v[j] : v[j];
  };
  precondition(r, z);
  p = z;
  double rz = r.dot(z);
  const double bnorm = b.norm();
  const int max_iterations = static_cast<int>(std::min<Index>(m_ + 10, kBorderMaxIterations));
  bool converged = bnorm == 0;
  for (int it = 0; it < max_iterations && !converged && ok; ++it) {
    apply_Gt(p, t);
    ok = A_->solve(t.data(), s.data()) && ok;
    apply_G(s, q);
    const double pq = p.dot(q);
    if (!(pq > 0)) break;
    const double alpha = rz / pq;
    L += alpha * p;
    u += alpha * s;
    r -= alpha * q;
    ++border_iterations_;
    if (r.norm() <= kBorderTol * bnorm) converged = true;
    precondition(r, z);
    const double rz_new = r.dot(z);
    p = z + (rz_new / rz) * p;
    rz = rz_new;
  }
  x = w - u;
  return ok && converged && L.allFinite() && x.allFinite();
}

// CG stops at kBorderTol, so the solution is refined against the bordered system itself (A's own
// values, not A_rho's): up to kRefinements further passes on its residual, each kept only if it
// lowers that residual (near-dependent rows, as 1-ring zones make, leave a residual at rounding
// level in directions where CG on it diverges), so that Newton sees the directions a direct solve
// of the KKT matrix gives.
bool BorderedSolver::solve_sparse(const double* r1, const double* r2, double* x, double* l) {
  const Eigen::Map<const Eigen::VectorXd> R1(r1, n_), R2(r2, m_);
  Eigen::VectorXd xs, ls, e1, e2;
  if (on_kkt_ || !border_pass(R1, R2, xs, ls)) return solve_kkt(R1, R2, x, l);  // KLU already, or CG failed
  auto residual = [&](const Eigen::VectorXd& xv, const Eigen::VectorXd& lv) {
    Eigen::VectorXd gtl, gx;
    e1 = R1;
    a_pattern_.add_product(a_values_.data(), xv.data(), -1.0, e1.data());
    apply_Gt(lv, gtl);
    e1 -= gtl;
    apply_G(xv, gx);
    e2 = R2 - gx;
    return std::sqrt(e1.squaredNorm() + e2.squaredNorm());
  };
  const double scale = std::sqrt(R1.squaredNorm() + R2.squaredNorm());
  double res = residual(xs, ls);
  for (int k = 0; k < kRefinements && res > 1e-14 * scale; ++k) {
    Eigen::VectorXd dx, dl;
    if (!border_pass(e1, e2, dx, dl)) break;
    const Eigen::VectorXd xn = xs + dx, ln = ls + dl;
    const double rn = residual(xn, ln);
    if (!(rn < res)) break;
    xs = xn;
    ls = ln;
    res = rn;
  }
  if (!(res <= kResidualMax * scale)) return solve_kkt(R1, R2, x, l);  // CG's answer is not the KKT system's
  Eigen::Map<Eigen::VectorXd>(x, n_) = xs;
  Eigen::Map<Eigen::VectorXd>(l, m_) = ls;
  return true;
}

// x_P = r2_P / c from the pinning rows; the other dofs and rows from the inner system with x_P's
// part moved to the right-hand side; then each pinning row's multiplier from its dof's row of the
// first block, c l_j = r1_i - (A x)_i - sum over the other rows of G_oi l_o.
bool BorderedSolver::solve_pinned(const double* r1, const double* r2, double* x, double* l) {
  const Pins& p = *pins_;
  Eigen::Map<Eigen::VectorXd> X(x, n_), L(l, m_);
  X.setZero();
  for (std::size_t k = 0; k < p.dof.size(); ++k) X[p.dof[k]] = r2[p.row[k]] / G_[p.row[k]][0];
  Eigen::VectorXd e = Eigen::Map<const Eigen::VectorXd>(r1, n_);
  a_pattern_.add_product(a_values_.data(), x, -1.0, e.data());  // r1 - A x_P
  const Index nf = static_cast<Index>(p.free_dofs.size()), mo = static_cast<Index>(p.other_rows.size());
  Eigen::VectorXd f1(nf), f2(mo), xf(nf), lo(mo);
  for (Index i = 0; i < nf; ++i) f1[i] = e[p.free_dofs[i]];
  for (Index o = 0; o < mo; ++o) {
    const Index j = p.other_rows[o];
    double s = r2[j];
    for (std::size_t k = 0; k < rows_[j].size(); ++k) s -= G_[j][k] * X[rows_[j][k]];
    f2[o] = s;
  }
  if (!p.inner->solve(f1.data(), f2.data(), xf.data(), lo.data())) return false;
  for (Index i = 0; i < nf; ++i) X[p.free_dofs[i]] = xf[i];
  L.setZero();
  for (Index o = 0; o < mo; ++o) L[p.other_rows[o]] = lo[o];
  e = Eigen::Map<const Eigen::VectorXd>(r1, n_);
  a_pattern_.add_product(a_values_.data(), x, -1.0, e.data());
  for (Index o = 0; o < mo; ++o) {
    const Index j = p.other_rows[o];
    for (std::size_t k = 0; k < rows_[j].size(); ++k) e[rows_[j][k]] -= G_[j][k] * lo[o];
  }
  for (std::size_t k = 0; k < p.dof.size(); ++k) L[p.row[k]] = e[p.dof[k]] / G_[p.row[k]][0];
  return X.allFinite() && L.allFinite();
}

}  // namespace isochor
