#include "bordered.hpp"

namespace isochor {

BorderedSolver::BorderedSolver(const SparsePattern& A, const std::vector<std::vector<Index>>& rows,
                               SymmetricSolverKind kind, double tol)
    : rows_(rows), n_(A.n), m_(static_cast<Index>(rows.size())), A_(make_symmetric_solver(A, kind, tol)) {
  Gt_.setZero(n_, m_);
  Z_.setZero(n_, m_);
}

bool BorderedSolver::factor(const double* A_values) { return A_->factor(A_values); }

bool BorderedSolver::set_borders(const std::vector<std::vector<double>>& G) {
  if (m_ == 0) return true;
  Gt_.setZero();
  for (Index j = 0; j < m_; ++j)
    for (std::size_t k = 0; k < G[j].size(); ++k) Gt_(rows_[j][k], j) = G[j][k];
  bool ok = true;
  for (Index j = 0; j < m_; ++j) ok = A_->solve(Gt_.col(j).data(), Z_.col(j).data()) && ok;
  C_.compute(Gt_.transpose() * Z_);
  return ok;
}

bool BorderedSolver::solve(const double* r1, const double* r2, double* x, double* l) {
  Eigen::Map<Eigen::VectorXd> y(x, n_);
  const bool ok = A_->solve(r1, x);
  if (m_ == 0) return ok;
  Eigen::Map<Eigen::VectorXd> dl(l, m_);
  dl = C_.solve(Gt_.transpose() * y - Eigen::Map<const Eigen::VectorXd>(r2, m_));
  y -= Z_ * dl;
  return ok;
}

}  // namespace isochor
