#include "isochor/initial_state.hpp"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <cmath>
#include <stdexcept>
#include <string>

namespace isochor {

void check_system(const ConstrainedSystem& sys) {
  const Index n = sys.num_dofs(), per = sys.dofs_per_group();
  if (per < 1 || n % per != 0)
    throw std::invalid_argument("the system has " + std::to_string(n) + " dofs, not a multiple of dofs_per_group() = " +
                                std::to_string(per) + " (override dofs_per_group() for groups other than x, y, z)");
  if (sys.mass().size() != n || !(sys.mass().array() > 0).all())
    throw std::invalid_argument("the system's mass() must hold " + std::to_string(n) + " positive entries");
  if (static_cast<Index>(sys.constraint_rows().size()) != sys.num_constraints())
    throw std::invalid_argument("the system's constraint_rows() must hold num_constraints() = " +
                                std::to_string(sys.num_constraints()) + " rows");
  for (const auto& row : sys.constraint_rows())
    for (Index d : row)
      if (d < 0 || d >= n) throw std::invalid_argument("a constraint row names dof " + std::to_string(d) + " outside 0.." + std::to_string(n - 1));
}

void consistent_initial_state(ConstrainedSystem& sys, double t0, VectorXd& q, VectorXd& v, VectorXd& a, VectorXd& lambda) {
  const Index n = sys.num_dofs(), m = sys.num_constraints();
  sys.initial_state(t0, q, v);
  const VectorXd& M = sys.mass();
  const VectorXd Minv = M.cwiseInverse();
  std::vector<std::vector<double>> G(m);
  for (Index j = 0; j < m; ++j) G[j].resize(sys.constraint_rows()[j].size());
  auto sparse_G = [&]() {
    std::vector<Eigen::Triplet<double>> tr;
    for (Index j = 0; j < m; ++j)
      for (std::size_t k = 0; k < G[j].size(); ++k) tr.emplace_back(j, sys.constraint_rows()[j][k], G[j][k]);
    Eigen::SparseMatrix<double> S(m, n);
    S.setFromTriplets(tr.begin(), tr.end());
    return S;
  };
  VectorXd g(m), gt(m);
  if (m > 0) {
    // 1. Positions onto g = 0: minimum-norm (mass-weighted) Newton steps.
    for (int it = 0; it < 50; ++it) {
      sys.constraint(t0, q, g);
      sys.constraint_jacobian(t0, q, G, nullptr);
      if (g.norm() < 1e-14 * (1.0 + q.norm())) break;
      const Eigen::SparseMatrix<double> S = sparse_G();
      const Eigen::SparseMatrix<double> A = S * Minv.asDiagonal() * S.transpose();
      Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(A);
      q -= Minv.asDiagonal() * (S.transpose() * ldlt.solve(g));
    }
    // 2. Velocities: [M G^T; G 0][v; nu] = [M v0; -g_t].
    sys.constraint_jacobian(t0, q, G, &gt);
    const Eigen::SparseMatrix<double> S = sparse_G();
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(Eigen::SparseMatrix<double>(S * Minv.asDiagonal() * S.transpose()));
    v -= Minv.asDiagonal() * (S.transpose() * ldlt.solve(VectorXd(S * v + gt)));
    // 3. Accelerations: M a + G^T lambda = f, G a = -w, where w = d/dt (G v + g_t) at a = 0,
    //    taken by a central difference along x(t +- h) = x +- h v (drivers exact).
    VectorXd f(n);
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
    lambda = ldlt.solve(VectorXd(S * Minv.cwiseProduct(f) + w));
    a = Minv.cwiseProduct(f - S.transpose() * lambda);
  } else {
    VectorXd f(n);
    sys.force(t0, q, v, f);
    a = Minv.cwiseProduct(f);
    lambda.resize(0);
  }
}

}  // namespace isochor
