#include "isochor/core/paint.hpp"

#include <nanoflann.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>

#include "isochor/base/error.hpp"

namespace isochor {
namespace {
using KdTree = nanoflann::KDTreeEigenMatrixAdaptor<Points, 3, nanoflann::metric_L2_Simple, false>;
}  // namespace

std::vector<std::vector<double>> paint_membership(const PaintedPoints& p, const PaintRule& rule) {
  const std::size_t n = static_cast<std::size_t>(p.x.cols());
  std::vector<std::vector<double>> in(rule.zones.size(), std::vector<double>(n, 0.0));
  auto need = [&](const std::string& name) {
    const auto* v = p.find(name);
    if (!v) {
      std::string have;
      for (const auto& h : p.names) have += (have.empty() ? "" : ", ") + h;
      throw Error(p.path + ": no vertex property \"" + name + "\" (it has: " + (have.empty() ? "none" : have) + ")");
    }
    return v;
  };
  switch (rule.by) {
    case PaintRule::By::labels: {
      const auto* L = need(rule.property);
      for (std::size_t z = 0; z < rule.zones.size(); ++z)
        for (std::size_t i = 0; i < n; ++i) in[z][i] = (*L)[i] == static_cast<double>(rule.labels[z]);
      break;
    }
    case PaintRule::By::colors: {
      const auto *r = need("red"), *g = need("green"), *b = need("blue");
      for (std::size_t i = 0; i < n; ++i) {
        // The nearest listed colour within the tolerance (one zone per vertex).
        const Eigen::Vector3d c((*r)[i], (*g)[i], (*b)[i]);
        int best = -1;
        double best_d = rule.color_tolerance;
        for (std::size_t z = 0; z < rule.zones.size(); ++z) {
          const double d = (c - rule.colors[z]).norm();
          if (d <= best_d) best = static_cast<int>(z), best_d = d;
        }
        if (best >= 0) in[best][i] = 1;
      }
      break;
    }
    case PaintRule::By::weights:
      for (std::size_t z = 0; z < rule.zones.size(); ++z) {
        const auto* w = need(rule.weights[z]);
        for (std::size_t i = 0; i < n; ++i) in[z][i] = (*w)[i];
      }
      break;
  }
  return in;
}

Eigen::Vector3d barycentric(const Eigen::Vector3d& q, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                            const Eigen::Vector3d& c) {
  const Eigen::Vector3d u = b - a, w = c - a, r = q - a;
  const double uu = u.dot(u), uw = u.dot(w), ww = w.dot(w), det = uu * ww - uw * uw;
  if (!(det > 0)) return Eigen::Vector3d(1, 0, 0);
  const double l1 = (ww * r.dot(u) - uw * r.dot(w)) / det, l2 = (uu * r.dot(w) - uw * r.dot(u)) / det;
  return Eigen::Vector3d(1 - l1 - l2, l1, l2);
}

Eigen::Vector3d closest_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                    const Eigen::Vector3d& c) {
  // Voronoi regions of the vertices, edges and face (Ericson, Real-Time Collision Detection, 5.1.5).
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

std::vector<std::vector<int>> painted_zones(const Mesh& mesh, const PaintedPoints& p,
                                            const std::vector<std::vector<double>>& membership, double tolerance) {
  const Points& X = mesh.rest_positions();
  const std::size_t Z = membership.size();
  // Surface nodes: the paint of the nearest painted point.
  KdTree painted(3, std::cref(p.x), 10);
  std::vector<std::vector<double>> node_in(Z, std::vector<double>(static_cast<std::size_t>(mesh.num_nodes()), 0.0));
  for (int v : mesh.surface_nodes()) {
    Eigen::Index nearest = 0;
    double d2 = 0;
    painted.index->knnSearch(X.col(v).data(), 1, &nearest, &d2);
    if (std::sqrt(d2) > tolerance) {
      char buf[300];
      std::snprintf(buf, sizeof buf,
                    ": surface node %d at [%g, %g, %g] is %.3g m from the nearest painted vertex (more than %g m: "
                    "expected the paint of this mesh's surface)",
                    v, X(0, v), X(1, v), X(2, v), std::sqrt(d2), tolerance);
      throw Error(p.path + buf);
    }
    for (std::size_t z = 0; z < Z; ++z) node_in[z][v] = membership[z][static_cast<std::size_t>(nearest)];
  }
  const auto& S = mesh.surface();
  Points centroid(3, static_cast<Eigen::Index>(S.size()));
  double reach = 0;  // the largest distance from a triangle's centroid to its corners
  for (std::size_t f = 0; f < S.size(); ++f) {
    centroid.col(f) = (X.col(S[f][0]) + X.col(S[f][1]) + X.col(S[f][2])) / 3.0;
    for (int v : S[f]) reach = std::max(reach, (X.col(v) - centroid.col(f)).norm());
  }
  // Tets: the paint at the surface point nearest to the centroid, interpolated linearly on its
  // triangle. The nearest triangle's centroid is within (the distance to the nearest centroid)
  // + reach: search that ball exactly.
  KdTree tris(3, std::cref(centroid), 10);
  std::vector<std::vector<int>> zones(Z);
  std::vector<std::pair<Eigen::Index, double>> found;
  for (int e = 0; e < mesh.num_tets(); ++e) {
    const Tet& t = mesh.tets()[e];
    const Eigen::Vector3d c = (X.col(t[0]) + X.col(t[1]) + X.col(t[2]) + X.col(t[3])) / 4.0;
    Eigen::Index nearest = 0;
    double d2 = 0;
    tris.index->knnSearch(c.data(), 1, &nearest, &d2);
    const double r = std::sqrt(d2) + reach;
    found.clear();
    tris.index->radiusSearch(c.data(), r * r * (1 + 1e-12), found, nanoflann::SearchParams());
    std::size_t best = static_cast<std::size_t>(nearest);
    double best_d = std::numeric_limits<double>::infinity();
    Eigen::Vector3d at = c;
    for (const auto& item : found) {
      const Tri& f = S[static_cast<std::size_t>(item.first)];
      const Eigen::Vector3d q = closest_on_triangle(c, X.col(f[0]), X.col(f[1]), X.col(f[2]));
      const double d = (q - c).squaredNorm();
      if (d < best_d) best_d = d, best = static_cast<std::size_t>(item.first), at = q;
    }
    const Tri& f = S[best];
    const Eigen::Vector3d l = barycentric(at, X.col(f[0]), X.col(f[1]), X.col(f[2]));
    for (std::size_t z = 0; z < Z; ++z) {
      const double paint = l[0] * node_in[z][f[0]] + l[1] * node_in[z][f[1]] + l[2] * node_in[z][f[2]];
      if (paint >= 0.5) zones[z].push_back(e);
    }
  }
  return zones;
}

std::vector<std::vector<int>> connected_pieces(const Mesh& mesh, const std::vector<int>& tets) {
  // Tets sharing a node are connected (not only through faces: a tet that touches a zone along an
  // edge, as the zone's border on a fine mesh leaves some, is not a piece of its own).
  std::vector<int> parent(tets.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto root = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  std::vector<int> node_owner(static_cast<std::size_t>(mesh.num_nodes()), -1);
  for (std::size_t k = 0; k < tets.size(); ++k)
    for (int v : mesh.tets()[tets[k]]) {
      if (node_owner[v] < 0)
        node_owner[v] = static_cast<int>(k);
      else
        parent[root(static_cast<int>(k))] = root(node_owner[v]);
    }
  std::map<int, std::vector<int>> pieces;
  for (std::size_t k = 0; k < tets.size(); ++k) pieces[root(static_cast<int>(k))].push_back(tets[k]);
  std::vector<std::vector<int>> out;
  for (auto& [r, v] : pieces) out.push_back(std::move(v));
  std::stable_sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.size() > b.size(); });
  return out;
}

}  // namespace isochor
