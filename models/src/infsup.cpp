#include "isochor/models/infsup.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <string>

#include "isochor/base/error.hpp"

namespace isochor {

namespace {

using SpMat = Eigen::SparseMatrix<double>;
using Triplets = std::vector<Eigen::Triplet<double>>;

// The free directions of every node as columns of T (3 N x dofs): none for a fixed node, the
// orthogonal complement of its held directions for a node on rollers, all three otherwise.
SpMat free_directions(int num_nodes, const std::vector<int>& fixed,
                      const std::vector<std::pair<int, Eigen::Vector3d>>& held) {
  std::vector<char> is_fixed(num_nodes, 0);
  for (int n : fixed) is_fixed[n] = 1;
  std::vector<std::vector<Eigen::Vector3d>> dirs(num_nodes);
  for (const auto& [n, d] : held) dirs[n].push_back(d);
  Triplets t;
  int col = 0;
  for (int n = 0; n < num_nodes; ++n) {
    if (is_fixed[n]) continue;
    Eigen::Matrix3d basis = Eigen::Matrix3d::Identity();
    int rank = 0;
    if (!dirs[n].empty()) {
      Eigen::Matrix3Xd H(3, dirs[n].size());
      for (std::size_t k = 0; k < dirs[n].size(); ++k) H.col(k) = dirs[n][k];
      Eigen::ColPivHouseholderQR<Eigen::Matrix3Xd> qr(H);
      rank = static_cast<int>(qr.rank());
      basis = qr.householderQ();
    }
    for (int c = rank; c < 3; ++c, ++col)
      for (int i = 0; i < 3; ++i)
        if (basis(i, c) != 0) t.emplace_back(3 * n + i, col, basis(i, c));
  }
  SpMat T(3 * num_nodes, col);
  T.setFromTriplets(t.begin(), t.end());
  return T;
}

// The H1 norm's matrix (|grad v|^2 + |v|^2 / L^2, consistent mass) and the zones' divergence rows
// (G(j, 3a + i) = sum over zone j's tets of V (grad N_a)_i), over every node's three directions.
void assemble(const Mesh& mesh, const std::vector<std::vector<int>>& zones, SpMat& K, SpMat& G) {
  const Points& X = mesh.rest_positions();
  const Eigen::Vector3d mean = X.rowwise().mean();
  const double L = 2 * (X.colwise() - mean).colwise().norm().maxCoeff();
  const int N = mesh.num_nodes(), E = mesh.num_tets();
  std::vector<Eigen::Matrix<double, 3, 4>> grad(E);
  Triplets k;
  k.reserve(static_cast<std::size_t>(E) * 48);
  for (int e = 0; e < E; ++e) {
    const Tet& t = mesh.tets()[e];
    Eigen::Matrix3d Dm;
    for (int c = 0; c < 3; ++c) Dm.col(c) = X.col(t[c + 1]) - X.col(t[0]);
    const double V = Dm.determinant() / 6;
    const Eigen::Matrix3d Dinv = Dm.inverse();  // rows: grad N_1..N_3
    grad[e].rightCols<3>() = V * Dinv.transpose();
    grad[e].col(0) = -grad[e].rightCols<3>().rowwise().sum();
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) {
        const double value = grad[e].col(a).dot(grad[e].col(b)) / V + V / (20 * L * L) * (a == b ? 2 : 1);
        for (int i = 0; i < 3; ++i) k.emplace_back(3 * t[a] + i, 3 * t[b] + i, value);
      }
  }
  K.resize(3 * N, 3 * N);
  K.setFromTriplets(k.begin(), k.end());
  Triplets g;
  for (std::size_t j = 0; j < zones.size(); ++j)
    for (int e : zones[j])
      for (int a = 0; a < 4; ++a)
        for (int i = 0; i < 3; ++i) g.emplace_back(static_cast<int>(j), 3 * mesh.tets()[e][a] + i, grad[e](i, a));
  G.resize(static_cast<Eigen::Index>(zones.size()), 3 * N);
  G.setFromTriplets(g.begin(), g.end());
}

// M_ij = the volume the zones i and j share.
Eigen::MatrixXd zone_gram(const Mesh& mesh, const std::vector<std::vector<int>>& zones) {
  std::vector<std::vector<int>> of_tet(mesh.num_tets());
  for (std::size_t j = 0; j < zones.size(); ++j)
    for (int e : zones[j]) of_tet[e].push_back(static_cast<int>(j));
  const auto m = static_cast<Eigen::Index>(zones.size());
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(m, m);
  for (int e = 0; e < mesh.num_tets(); ++e)
    for (int i : of_tet[e])
      for (int j : of_tet[e]) M(i, j) += mesh.rest_volumes()[e];
  return M;
}

}  // namespace

InfSup infsup_constant(const Mesh& mesh, const std::vector<std::vector<int>>& zones, const std::vector<int>& fixed,
                       const std::vector<std::pair<int, Eigen::Vector3d>>& held, int max_zones) {
  const int m = static_cast<int>(zones.size());
  if (m == 0) throw Error("inf-sup: the scene has no zones (expected zones in [zones])");
  if (m > max_zones)
    throw Error("inf-sup: " + std::to_string(m) + " zones (expected at most " + std::to_string(max_zones) +
                ": the test solves a dense eigenproblem of one row per zone; use a coarser mesh)");
  const SpMat T = free_directions(mesh.num_nodes(), fixed, held);
  SpMat K, G;
  assemble(mesh, zones, K, G);
  const SpMat Kr = T.transpose() * K * T;
  const SpMat Gr = G * T;
  const Eigen::MatrixXd M = zone_gram(mesh, zones);
  // M is positive definite exactly when the zones' indicators are independent.
  const Eigen::LLT<Eigen::MatrixXd> llt(M);
  const double pivot = llt.info() == Eigen::Success ? llt.matrixLLT().diagonal().minCoeff() : 0.0;
  if (!(pivot > 1e-5 * std::sqrt(M.diagonal().maxCoeff())))
    throw Error(
        "inf-sup: the zones are linearly dependent (e.g. the global zone beside zones that cover the "
        "body: their sum); expected independent zones");
  Eigen::SimplicialLLT<SpMat> chol(Kr);
  if (chol.info() != Eigen::Success) throw Error("inf-sup: the H1 matrix could not be factored");
  // S = G K^-1 G^T, a block of right-hand sides at a time.
  Eigen::MatrixXd S(m, m);
  const SpMat Gt = Gr.transpose();
  for (int j0 = 0; j0 < m; j0 += 64) {
    const int nb = std::min(64, m - j0);
    const Eigen::MatrixXd X = chol.solve(Eigen::MatrixXd(Gt.middleCols(j0, nb)));
    S.middleCols(j0, nb) = Gr * X;
  }
  S = 0.5 * (S + S.transpose()).eval();
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(S, M, Eigen::EigenvaluesOnly | Eigen::Ax_lBx);
  if (es.info() != Eigen::Success) throw Error("inf-sup: the eigenproblem did not converge");
  const Eigen::VectorXd& ev = es.eigenvalues();
  InfSup r;
  r.zones = m;
  r.dofs = static_cast<int>(Kr.rows());
  r.beta = std::sqrt(std::max(0.0, ev(0)));
  r.beta_next = m > 1 ? std::sqrt(std::max(0.0, ev(1))) : r.beta;
  for (Eigen::Index i = 0; i < ev.size(); ++i) r.zero_modes += ev(i) < 1e-10 * ev(ev.size() - 1);
  return r;
}

}  // namespace isochor
