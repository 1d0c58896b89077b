#include "isochor/core/embedding.hpp"

#include <nanoflann.hpp>

#include <Eigen/Dense>
#include <functional>
#include <limits>

namespace isochor {

namespace {

using KdTree = nanoflann::KDTreeEigenMatrixAdaptor<Points, 3, nanoflann::metric_L2_Simple, false>;

// Barycentric weights of p in the tet with nodes a, b, c, d.
Eigen::Vector4d barycentric(const Points& X, const Tet& t, const Eigen::Vector3d& p) {
  Eigen::Matrix3d D;
  D << X.col(t[1]) - X.col(t[0]), X.col(t[2]) - X.col(t[0]), X.col(t[3]) - X.col(t[0]);
  const Eigen::Vector3d l = D.partialPivLu().solve(p - X.col(t[0]));
  return Eigen::Vector4d(1 - l.sum(), l[0], l[1], l[2]);
}

}  // namespace

Embedding embed_points(const Mesh& mesh, const Points& p) {
  const Points& X = mesh.rest_positions();
  Points centroid(3, mesh.num_tets());
  for (int e = 0; e < mesh.num_tets(); ++e) {
    const Tet& t = mesh.tets()[e];
    centroid.col(e) = 0.25 * (X.col(t[0]) + X.col(t[1]) + X.col(t[2]) + X.col(t[3]));
  }
  KdTree tree(3, std::cref(centroid), 10);
  Embedding out;
  out.tet.resize(static_cast<std::size_t>(p.cols()));
  out.weights.resize(4, p.cols());
  // The tets whose centroids are nearest: the point lies in one of them unless it is outside the
  // mesh or the tets near it are far from regular; then the tet it is least outside of (the
  // largest smallest weight) is the nearest tet in the barycentric sense.
  const std::size_t k = std::min<std::size_t>(32, static_cast<std::size_t>(mesh.num_tets()));
  std::vector<Eigen::Index> found(k);
  std::vector<double> d2(k);
  for (Eigen::Index v = 0; v < p.cols(); ++v) {
    const Eigen::Vector3d q = p.col(v);
    const std::size_t n = tree.index->knnSearch(q.data(), k, found.data(), d2.data());
    double best = -std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < n && best < 0; ++i) {
      const int e = static_cast<int>(found[i]);
      const Eigen::Vector4d w = barycentric(X, mesh.tets()[e], q);
      if (w.minCoeff() > best) {
        best = w.minCoeff();
        out.tet[v] = e;
        out.weights.col(v) = w;
      }
    }
  }
  return out;
}

Points Embedding::positions(const Mesh& mesh, const Points& x) const {
  Points out(3, weights.cols());
  for (Eigen::Index v = 0; v < weights.cols(); ++v) {
    const Tet& t = mesh.tets()[tet[v]];
    out.col(v) = weights(0, v) * x.col(t[0]) + weights(1, v) * x.col(t[1]) + weights(2, v) * x.col(t[2]) +
                 weights(3, v) * x.col(t[3]);
  }
  return out;
}

}  // namespace isochor
