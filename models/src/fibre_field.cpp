// Fibre fields (the Laplace solve between a muscle's origin and insertion) and activation curves.
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <map>

#include "isochor/base/error.hpp"
#include "isochor/models/muscle.hpp"
#include "isochor/models/skeleton.hpp"

namespace isochor {

double ActivationCurve::joint_angle(double t, const Skeleton& skeleton) const {
  return skeleton.bones().at(bone).motion.displacement(t)[axis];
}

double ActivationCurve::at(double t, const Skeleton* skeleton, double scale) const {
  double a = value;
  if (source == Source::time) a = curve.displacement(t).x();
  if (source == Source::joint) {
    if (!skeleton) throw Error("activation keyed by a joint angle without a skeleton");
    a = curve.displacement(joint_angle(t, *skeleton)).x();
  }
  if (source == Source::channel) a = curve.displacement(channel.displacement(t).x()).x();
  return std::clamp(scale * a, 0.0, 1.0);
}

namespace {
// The muscle's nodes numbered 0.. in order of appearance, and each tet's shape gradients.
struct SubMesh {
  std::map<int, int> local;  // mesh node -> local index
  std::vector<std::array<Vec3, 4>> b;
  std::vector<double> volume;
};

SubMesh sub_mesh(const Mesh& mesh, const std::vector<int>& tets) {
  SubMesh m;
  const Points& X = mesh.rest_positions();
  for (int e : tets) {
    const Tet& t = mesh.tets()[e];
    for (int k = 0; k < 4; ++k) m.local.emplace(t[k], static_cast<int>(m.local.size()));
    const TetShape s = TetShape::make(X.col(t[0]), X.col(t[1]), X.col(t[2]), X.col(t[3]));
    std::array<Vec3, 4> b;
    for (int a = 1; a < 4; ++a) b[a] = s.Dm_inv.row(a - 1).transpose();
    b[0] = -(b[1] + b[2] + b[3]);
    m.b.push_back(b);
    m.volume.push_back(std::abs(s.rest_volume));
  }
  return m;
}

Vec3 centroid(const Mesh& mesh, const std::vector<int>& nodes) {
  Vec3 c = Vec3::Zero();
  for (int n : nodes) c += mesh.rest_positions().col(n);
  return c / static_cast<double>(nodes.size());
}
}  // namespace

std::vector<Vec3> laplace_fibres(const Mesh& mesh, const std::vector<int>& tets, const std::vector<int>& origin,
                                 const std::vector<int>& insertion) {
  const SubMesh m = sub_mesh(mesh, tets);
  const int n = static_cast<int>(m.local.size());
  // Dirichlet values: 0 at the origin, 1 at the insertion (a node in both is an error).
  std::vector<double> fixed(n, -1.0);
  std::vector<int> in_origin, in_insertion;
  for (int v : origin)
    if (auto it = m.local.find(v); it != m.local.end()) fixed[it->second] = 0.0, in_origin.push_back(v);
  for (int v : insertion)
    if (auto it = m.local.find(v); it != m.local.end()) {
      if (fixed[it->second] == 0.0)
        throw Error("node " + std::to_string(v) + " is in both the origin and the insertion");
      fixed[it->second] = 1.0;
      in_insertion.push_back(v);
    }
  if (in_origin.empty()) throw Error("the origin holds no node of the muscle");
  if (in_insertion.empty()) throw Error("the insertion holds no node of the muscle");
  // The free nodes' system K_ff u_f = -K_fd u_d, K_ab = V b_a . b_b.
  std::vector<int> free_index(n, -1);
  int nf = 0;
  for (int i = 0; i < n; ++i)
    if (fixed[i] < 0) free_index[i] = nf++;
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(nf);
  for (std::size_t k = 0; k < tets.size(); ++k) {
    const Tet& t = mesh.tets()[tets[k]];
    for (int a = 0; a < 4; ++a) {
      const int i = free_index[m.local.at(t[a])];
      if (i < 0) continue;
      for (int c = 0; c < 4; ++c) {
        const int lc = m.local.at(t[c]);
        const double K = m.volume[k] * m.b[k][a].dot(m.b[k][c]);
        if (free_index[lc] >= 0)
          entries.emplace_back(i, free_index[lc], K);
        else
          rhs[i] -= K * fixed[lc];
      }
    }
  }
  Eigen::VectorXd u_free = Eigen::VectorXd::Zero(nf);
  if (nf > 0) {
    Eigen::SparseMatrix<double> K(nf, nf);
    K.setFromTriplets(entries.begin(), entries.end());
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(K);
    if (ldlt.info() != Eigen::Success)
      throw Error("the Laplace solve failed: a piece of the muscle touches neither its origin nor its insertion");
    u_free = ldlt.solve(rhs);
  }
  const Vec3 along = (centroid(mesh, in_insertion) - centroid(mesh, in_origin)).normalized();
  std::vector<Vec3> fibre;
  for (std::size_t k = 0; k < tets.size(); ++k) {
    const Tet& t = mesh.tets()[tets[k]];
    Vec3 g = Vec3::Zero();
    for (int a = 0; a < 4; ++a) {
      const int l = m.local.at(t[a]);
      g += (fixed[l] >= 0 ? fixed[l] : u_free[free_index[l]]) * m.b[k][a];
    }
    // grad u of a tet whose nodes all hold one Dirichlet value vanishes (up to rounding).
    const double scale = 1.0 / std::cbrt(m.volume[k]);
    fibre.push_back(g.norm() > 1e-9 * scale ? Vec3(g.normalized()) : along);
  }
  return fibre;
}

}  // namespace isochor
