#include "isochor/integrators/initial_state.hpp"
#include "isochor/base/error.hpp"

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace isochor {

void check_groups(const ConstrainedSystem& sys, const std::string& who) {
  const Index n = sys.num_dofs(), per = sys.dofs_per_group();
  if (n % per != 0)
    throw Error(who + " orders the dofs by groups of dofs_per_group() = " + std::to_string(per) +
                ", but the system has " + std::to_string(n) +
                " dofs, not a multiple of it (override dofs_per_group() for groups other than x, y, z)");
}

void check_system(const ConstrainedSystem& sys) {
  const Index n = sys.num_dofs(), per = sys.dofs_per_group();
  if (per < 1) throw Error("the system's dofs_per_group() must be at least 1, got " + std::to_string(per));
  if (sys.mass().size() != n || !(sys.mass().array() > 0).all())
    throw Error("the system's mass() must hold " + std::to_string(n) + " positive entries");
  if (static_cast<Index>(sys.constraint_rows().size()) != sys.num_constraints())
    throw Error("the system's constraint_rows() must hold num_constraints() = " +
                std::to_string(sys.num_constraints()) + " rows");
  for (const auto& row : sys.constraint_rows())
    for (Index d : row)
      if (d < 0 || d >= n)
        throw Error("a constraint row names dof " + std::to_string(d) + " outside 0.." + std::to_string(n - 1));
}

namespace {
// Rows of G in a sparse m x n matrix.
Eigen::SparseMatrix<double> sparse_rows(const ConstrainedSystem& sys, const std::vector<std::vector<double>>& G) {
  std::vector<Eigen::Triplet<double>> tr;
  for (std::size_t j = 0; j < G.size(); ++j)
    for (std::size_t k = 0; k < G[j].size(); ++k)
      tr.emplace_back(static_cast<Index>(j), sys.constraint_rows()[j][k], G[j][k]);
  Eigen::SparseMatrix<double> S(sys.num_constraints(), sys.num_dofs());
  S.setFromTriplets(tr.begin(), tr.end());
  return S;
}

// The Gram matrix A = G M^-1 G^T of the constraint rows, for the projections and the initial
// multipliers. Linearly dependent constraints (zones.global over patches that partition the mesh)
// make A singular: LDL^T's pivot there is rounding, and its solve would put a huge multiplier
// along the dependency. A pivot below 1e-12 of the largest one switches to the least-squares
// solution with the smallest norm (a complete orthogonal decomposition of the dense A): the
// dependent constraints are consistent, so the state is the same; only the split of their
// multipliers is chosen. Above kDenseLimit constraints that would be too slow; there the sparse
// LDL^T of A + delta I, delta = 1e-12 of A's largest pivot (ridge regression, whose solution
// tends to the smallest-norm one as delta -> 0), stands in for it: directions with eigenvalues
// below delta (the ones the pivot test calls dependent) get no multiplier, the others are solved
// to a relative error delta / eigenvalue. Irving's 1-ring zones on a held cube (4,913 zones of
// demos/cube_gravity.toml) are such a case: the pivot test flags them, and backward Euler runs
// them with every zone held to 4e-10 (docs/results/stability_cube).
class GramSolver {
 public:
  static constexpr Index kDenseLimit = 1000;  // a dense decomposition of 1000 x 1000: about 0.5 s
  explicit GramSolver(const Eigen::SparseMatrix<double>& S, const VectorXd& Minv) {
    const Eigen::SparseMatrix<double> A(S * Minv.asDiagonal() * S.transpose());
    ldlt_.compute(A);
    const VectorXd d = ldlt_.vectorD().cwiseAbs();
    if (ldlt_.info() == Eigen::Success && d.size() && d.minCoeff() > 1e-12 * d.maxCoeff()) return;
    dependent_ = true;
    if (A.rows() > kDenseLimit) {
      const double scale = d.size() && std::isfinite(d.maxCoeff()) && d.maxCoeff() > 0
                               ? d.maxCoeff()
                               : A.diagonal().cwiseAbs().maxCoeff();
      Eigen::SparseMatrix<double> I(A.rows(), A.cols());
      I.setIdentity();
      ldlt_.compute(A + 1e-12 * scale * I);
      if (ldlt_.info() != Eigen::Success)
        throw Error(std::to_string(A.rows()) +
                    " constraints that are linearly dependent (e.g. zones.global together with zones that partition "
                    "the mesh): remove the redundant zones");
      return;
    }
    dense_ = true;
    cod_.setThreshold(1e-12);
    cod_.compute(Eigen::MatrixXd(A));
  }
  VectorXd solve(const VectorXd& b) const { return dense_ ? VectorXd(cod_.solve(b)) : VectorXd(ldlt_.solve(b)); }
  bool dependent() const { return dependent_; }

 private:
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt_;
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod_;
  bool dense_ = false, dependent_ = false;
};
}  // namespace

bool constraints_dependent(ConstrainedSystem& sys, double t, const VectorXd& q) {
  const Index m = sys.num_constraints();
  if (m == 0) return false;
  std::vector<std::vector<double>> G(m);
  for (Index j = 0; j < m; ++j) G[j].resize(sys.constraint_rows()[j].size());
  sys.constraint_jacobian(t, q, G, nullptr);
  try {
    return GramSolver(sparse_rows(sys, G), sys.mass().cwiseInverse()).dependent();
  } catch (const Error&) {  // too many to decompose densely: dependent all the same
    return true;
  }
}

double constraint_error(const ConstrainedSystem& sys, const VectorXd& g) {
  double worst = 0;
  for (Index j = 0; j < g.size(); ++j)
    worst = std::max(worst, std::abs(g[j]) / sys.constraint_scale(static_cast<int>(j)));
  return worst;
}

void project_state(ConstrainedSystem& sys, double t, VectorXd& q, VectorXd& v) {
  const Index m = sys.num_constraints();
  if (m == 0) return;
  const VectorXd Minv = sys.mass().cwiseInverse();
  std::vector<std::vector<double>> G(m);
  for (Index j = 0; j < m; ++j) G[j].resize(sys.constraint_rows()[j].size());
  VectorXd g(m), gt(m);
  // 1. Positions: the nearest point of g = 0 in the mass norm, by Newton steps along M^-1 G^T
  //    (each step solves G M^-1 G^T nu = g). It stops at 1e-14 of each row's scale, or where
  //    rounding stops the error from halving.
  double last = std::numeric_limits<double>::infinity();
  for (int it = 0; it < 50; ++it) {
    sys.constraint(t, q, g);
    const double err = constraint_error(sys, g);
    if (err < 1e-14 || !(err < 0.5 * last)) break;
    last = err;
    sys.constraint_jacobian(t, q, G, nullptr);
    const Eigen::SparseMatrix<double> S = sparse_rows(sys, G);
    q -= Minv.asDiagonal() * (S.transpose() * GramSolver(S, Minv).solve(g));
  }
  // 2. Velocities: the nearest v (mass norm) with G v + dg/dt = 0, one linear solve.
  sys.constraint_jacobian(t, q, G, &gt);
  const Eigen::SparseMatrix<double> S = sparse_rows(sys, G);
  v -= Minv.asDiagonal() * (S.transpose() * GramSolver(S, Minv).solve(VectorXd(S * v + gt)));
}

void consistent_initial_state(ConstrainedSystem& sys, double t0, VectorXd& q, VectorXd& v, VectorXd& a,
                              VectorXd& lambda) {
  const Index n = sys.num_dofs(), m = sys.num_constraints();
  sys.initial_state(t0, q, v);
  const VectorXd Minv = sys.mass().cwiseInverse();
  VectorXd f(n);
  if (m > 0) {
    if (!sys.starts_from_stored_state()) project_state(sys, t0, q, v);
    std::vector<std::vector<double>> G(m);
    for (Index j = 0; j < m; ++j) G[j].resize(sys.constraint_rows()[j].size());
    sys.constraint_jacobian(t0, q, G, nullptr);
    const Eigen::SparseMatrix<double> S = sparse_rows(sys, G);
    const GramSolver gram(S, Minv);
    // 3. Accelerations: M a + G^T lambda = f, G a = -w, where w = d/dt (G v + g_t) at a = 0,
    //    taken by a central difference along x(t +- h) = x +- h v (drivers exact).
    sys.force(t0, q, v, f);
    const double h = 1e-6 * std::max(1.0, std::abs(t0));
    auto velocity_constraint = [&](double t, const VectorXd& qq) {
      std::vector<std::vector<double>> Gh(G);
      VectorXd gth(m);
      sys.constraint_jacobian(t, qq, Gh, &gth);
      VectorXd out = gth;
      for (Index j = 0; j < m; ++j)
        for (std::size_t k = 0; k < Gh[j].size(); ++k) out[j] += Gh[j][k] * v[sys.constraint_rows()[j][k]];
      return out;
    };
    const VectorXd w = (velocity_constraint(t0 + h, q + h * v) - velocity_constraint(t0 - h, q - h * v)) / (2 * h);
    lambda = gram.solve(VectorXd(S * Minv.cwiseProduct(f) + w));
    a = Minv.cwiseProduct(f - S.transpose() * lambda);
    sys.stored_multipliers(lambda);  // a resumed run: the multipliers it had there
  } else {
    sys.force(t0, q, v, f);
    a = Minv.cwiseProduct(f);
    lambda.resize(0);
  }
}

}  // namespace isochor
