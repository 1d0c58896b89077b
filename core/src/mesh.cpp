#include "isochor/core/mesh.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <unordered_map>

#include "isochor/base/error.hpp"

namespace isochor {

double tet_signed_volume(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                         const Eigen::Vector3d& d) {
  return (b - a).dot((c - a).cross(d - a)) / 6.0;
}

double tets_volume(const Points& x, const std::vector<Tet>& tets) {
  double v = 0.0;
  for (const Tet& t : tets) v += tet_signed_volume(x.col(t[0]), x.col(t[1]), x.col(t[2]), x.col(t[3]));
  return v;
}

double surface_volume(const Points& x, const std::vector<Tri>& surface) {
  double v = 0.0;
  for (const Tri& f : surface) v += x.col(f[0]).dot(x.col(f[1]).cross(x.col(f[2])));
  return v / 6.0;
}

namespace {

std::uint64_t edge_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(a) << 32) | static_cast<std::uint32_t>(b);
}

// Builds compressed rows from (row, value) pairs, values sorted and unique per row.
Adjacency build_adjacency(int rows, std::vector<std::pair<int, int>>& pairs) {
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  Adjacency a;
  a.offset.assign(rows + 1, 0);
  for (const auto& p : pairs) a.offset[p.first + 1]++;
  for (int i = 0; i < rows; ++i) a.offset[i + 1] += a.offset[i];
  a.index.resize(pairs.size());
  for (std::size_t k = 0; k < pairs.size(); ++k) a.index[k] = pairs[k].second;
  return a;
}

}  // namespace

SurfaceCheck check_surface(const std::vector<Tri>& surface) {
  SurfaceCheck c;
  std::unordered_map<std::uint64_t, int> undirected;
  std::unordered_map<std::uint64_t, int> directed;
  std::vector<int> nodes;
  undirected.reserve(surface.size() * 3);
  directed.reserve(surface.size() * 3);
  for (const Tri& f : surface) {
    for (int e = 0; e < 3; ++e) {
      int a = f[e], b = f[(e + 1) % 3];
      undirected[edge_key(a, b)]++;
      directed[(static_cast<std::uint64_t>(a) << 32) | static_cast<std::uint32_t>(b)]++;
      nodes.push_back(a);
    }
  }
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  // Report the smallest offending edge so that messages do not depend on hash order.
  std::uint64_t bad = ~std::uint64_t{0};
  for (const auto& [key, n] : undirected) {
    if (n == 1) c.boundary_edges++;
    if (n > 2) c.nonmanifold_edges++;
    if (n != 2) bad = std::min(bad, key);
  }
  if (bad != ~std::uint64_t{0}) c.first_bad_edge = {static_cast<int>(bad >> 32), static_cast<int>(bad & 0xffffffffu)};
  c.closed = c.boundary_edges == 0 && c.nonmanifold_edges == 0;
  c.oriented = std::all_of(directed.begin(), directed.end(), [](const auto& kv) { return kv.second == 1; });
  c.euler_characteristic =
      static_cast<int>(nodes.size()) - static_cast<int>(undirected.size()) + static_cast<int>(surface.size());
  return c;
}

std::vector<int> compact_unused_nodes(Points& x, std::vector<Tet>& tets,
                                      std::map<std::string, std::vector<int>>* node_sets) {
  const int n = static_cast<int>(x.cols());
  std::vector<int> remap(n, -1), kept;
  for (const Tet& t : tets)
    for (int v : t) {
      if (v < 0 || v >= n)
        throw Error("tet refers to node " + std::to_string(v) + ", expected 0.." + std::to_string(n - 1));
      remap[v] = 0;
    }
  for (int i = 0; i < n; ++i)
    if (remap[i] == 0) {
      remap[i] = static_cast<int>(kept.size());
      kept.push_back(i);
    }
  if (static_cast<int>(kept.size()) == n) return kept;
  Points y(3, kept.size());
  for (std::size_t i = 0; i < kept.size(); ++i) y.col(i) = x.col(kept[i]);
  x = std::move(y);
  for (Tet& t : tets)
    for (int& v : t) v = remap[v];
  if (node_sets) {
    for (auto& [name, set] : *node_sets) {
      std::vector<int> s;
      for (int v : set)
        if (remap[v] >= 0) s.push_back(remap[v]);
      set = std::move(s);
    }
  }
  return kept;
}

Mesh::Mesh(Points positions, std::vector<Tet> tets, const std::string& what)
    : X_(std::move(positions)), tets_(std::move(tets)) {
  const int n = num_nodes();
  const int T = num_tets();
  if (T == 0) throw Error(what + ": the mesh has no tetrahedra");
  if (!X_.allFinite()) throw Error(what + ": a node position is not finite");
  // Sizes a body can have, as for shapes and colliders: a mesh of 1e-300 m has masses and volumes
  // that underflow to 0, one of 1e300 m forces that overflow.
  if (n > 0) {
    const double across = (X_.rowwise().maxCoeff() - X_.rowwise().minCoeff()).maxCoeff();
    const double farthest = X_.cwiseAbs().maxCoeff();
    if (!(across >= 1e-6 && across <= 1e6) || farthest > 1e7) {
      char buf[200];
      std::snprintf(buf, sizeof buf,
                    ": the mesh is %.3g m across, its farthest node %.3g m from the origin (expected 1e-06 to 1e+06 "
                    "m across, within 1e+07 m: sizes are in metres)",
                    across, farthest);
      throw Error(what + buf);
    }
  }
  volume_.resize(T);
  double mean_abs = 0.0;
  for (int e = 0; e < T; ++e) {
    Tet& t = tets_[e];
    for (int v : t)
      if (v < 0 || v >= n)
        throw Error(what + ": tet " + std::to_string(e) + " refers to node " + std::to_string(v) + ", expected 0.." +
                    std::to_string(n - 1));
    volume_[e] = tet_signed_volume(X_.col(t[0]), X_.col(t[1]), X_.col(t[2]), X_.col(t[3]));
    mean_abs += std::abs(volume_[e]);
  }
  mean_abs /= T;
  for (int e = 0; e < T; ++e) {
    if (!(std::abs(volume_[e]) >= 1e-12 * mean_abs))
      throw Error(what + ": tet " + std::to_string(e) + " is degenerate (volume " + std::to_string(volume_[e]) +
                  ", expected |V| above 1e-12 of the mean " + std::to_string(mean_abs) + ")");
    if (volume_[e] < 0) {
      std::swap(tets_[e][2], tets_[e][3]);
      volume_[e] = -volume_[e];
      reoriented_++;
    }
    total_volume_ += volume_[e];
  }

  std::array<int, 4> overshared{};
  surface_ = boundary_faces(tets_, nullptr, &overshared);
  if (overshared[3] > 2)
    throw Error(what + ": face (" + std::to_string(overshared[0]) + ", " + std::to_string(overshared[1]) + ", " +
                std::to_string(overshared[2]) + ") is shared by " + std::to_string(overshared[3]) +
                " tets, expected at most 2");
  for (const Tri& f : surface_)
    for (int v : f) surface_nodes_.push_back(v);
  std::sort(surface_nodes_.begin(), surface_nodes_.end());
  surface_nodes_.erase(std::unique(surface_nodes_.begin(), surface_nodes_.end()), surface_nodes_.end());

  std::vector<std::pair<int, int>> pairs;
  pairs.reserve(4 * T);
  for (int e = 0; e < T; ++e)
    for (int v : tets_[e]) pairs.emplace_back(v, e);
  node_tets_ = build_adjacency(n, pairs);
  pairs.clear();
  pairs.reserve(12 * T);
  for (const Tet& t : tets_)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        if (a != b) pairs.emplace_back(t[a], t[b]);
  node_nodes_ = build_adjacency(n, pairs);
}

std::vector<int> Mesh::node_ring(int node, int k) const {
  if (node < 0 || node >= num_nodes())
    throw Error("node " + std::to_string(node) + " is not in the mesh (expected 0.." + std::to_string(num_nodes() - 1) +
                ")");
  std::vector<char> seen(num_nodes(), 0);
  std::vector<int> ring{node}, front{node};
  seen[node] = 1;
  for (int level = 0; level < k && !front.empty(); ++level) {
    std::vector<int> next;
    for (int v : front)
      for (const int* w = node_nodes_.begin(v); w != node_nodes_.end(v); ++w)
        if (!seen[*w]) {
          seen[*w] = 1;
          next.push_back(*w);
        }
    ring.insert(ring.end(), next.begin(), next.end());
    front = std::move(next);
  }
  std::sort(ring.begin(), ring.end());
  return ring;
}

std::vector<int> Mesh::tet_ring(int node, int k) const {
  if (k < 1) throw Error("tet ring: k = " + std::to_string(k) + ", expected k >= 1");
  std::vector<int> tets;
  for (int v : node_ring(node, k - 1)) tets.insert(tets.end(), node_tets_.begin(v), node_tets_.end(v));
  std::sort(tets.begin(), tets.end());
  tets.erase(std::unique(tets.begin(), tets.end()), tets.end());
  return tets;
}

std::vector<Tri> boundary_faces(const std::vector<Tet>& tets, const std::vector<int>* which,
                                std::array<int, 4>* overshared) {
  // Faces opposite each vertex of a positive tet, ordered so that their normals point outward.
  static constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  struct Face {
    std::array<int, 3> key;  // sorted nodes
    Tri tri;                 // oriented
  };
  std::vector<Face> faces;
  const std::size_t count = which ? which->size() : tets.size();
  faces.reserve(4 * count);
  for (std::size_t i = 0; i < count; ++i) {
    const Tet& t = tets[which ? static_cast<std::size_t>((*which)[i]) : i];
    for (const auto& f : kFace) {
      Tri tri{t[f[0]], t[f[1]], t[f[2]]};
      std::array<int, 3> key{tri[0], tri[1], tri[2]};
      std::sort(key.begin(), key.end());
      faces.push_back({key, tri});
    }
  }
  std::sort(faces.begin(), faces.end(), [](const Face& a, const Face& b) { return a.key < b.key; });
  std::vector<Tri> out;
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i + 1;
    while (j < faces.size() && faces[j].key == faces[i].key) ++j;
    if (j - i == 1) out.push_back(faces[i].tri);
    if (overshared && static_cast<int>(j - i) > (*overshared)[3])
      *overshared = {faces[i].key[0], faces[i].key[1], faces[i].key[2], static_cast<int>(j - i)};
    i = j;
  }
  return out;
}

ShapeDistance rest_shape_distance(const Points& X, const Points& x) {
  if (X.cols() != x.cols() || X.cols() == 0) throw Error("rest_shape_error: expected two point sets of one size");
  const Eigen::Vector3d cX = X.rowwise().mean(), cx = x.rowwise().mean();
  const Eigen::Matrix3d H = (x.colwise() - cx) * (X.colwise() - cX).transpose();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
  const Eigen::Matrix3d R = svd.matrixV() * D * svd.matrixU().transpose();  // R (x - cx) ~ X - cX
  const Eigen::VectorXd d = ((R * (x.colwise() - cx)).colwise() + cX - X).colwise().norm();
  const double diag = (X.rowwise().maxCoeff() - X.rowwise().minCoeff()).norm();
  return {std::sqrt(d.squaredNorm() / static_cast<double>(d.size())) / diag, d.maxCoeff() / diag};
}

double rest_shape_error(const Points& X, const Points& x) { return rest_shape_distance(X, x).largest; }

}  // namespace isochor
