#include <array>
#include <limits>
#include <algorithm>

#include "isochor/models/constraints.hpp"
#include "isochor/base/error.hpp"

namespace isochor {

const std::vector<Vec3>& VolumeConstraints::origins(const Points& x) const {
  // The mean current position of each constraint's boundary nodes. A closed surface's enclosed
  // volume does not depend on the origin (its oriented face areas sum to zero), so neither do its
  // gradient and Hessian, and the origin may follow the body, which keeps the face terms small
  // (a fixed origin cost digits: docs/decisions.md).
  // Kept in a member, so that the callbacks that call this allocate nothing after the first call.
  std::vector<Vec3>& o = origins_;
  o.assign(boundary_nodes_.size(), Vec3::Zero());
  for (std::size_t j = 0; j < boundary_nodes_.size(); ++j) {
    for (int v : boundary_nodes_[j]) o[j] += x.col(v);
    if (!boundary_nodes_[j].empty()) o[j] /= static_cast<double>(boundary_nodes_[j].size());
  }
  return o;
}

Vec12 VolumeConstraints::element_x(const Points& x, const Element& e, const std::vector<Vec3>& o) const {
  Vec12 v;
  for (int k = 0; k < 4; ++k) v.segment<3>(3 * k) = e.nodes[k] < 0 ? o[e.constraint] : Vec3(x.col(e.nodes[k]));
  return v;
}

VolumeConstraints VolumeConstraints::zones(const Mesh& mesh, const std::vector<std::vector<int>>& zone_tets,
                                           const DofMap& dofs, const Pattern& pattern) {
  // A zone's volume is the sum of its tets' signed volumes; the faces two of its tets share cancel
  // in that sum, so it equals the sum over the zone's boundary faces (outward) of the signed
  // volume of the tet (origin, face): the divergence theorem. Its gradient and Hessian then live
  // on the boundary nodes only (an interior node's contributions cancel exactly), and evaluating
  // them costs O(boundary) instead of O(volume): 6.8K faces instead of 64K tets for the global
  // zone of the fine ball. The origin follows the zone (origins()): small terms, little cancellation.
  VolumeConstraints c;
  c.zone_tets_ = zone_tets;
  for (int j = 0; j < static_cast<int>(zone_tets.size()); ++j) {
    double v0 = 0;
    for (int e : zone_tets[j]) v0 += mesh.rest_volumes()[e];
    for (const Tri& f : boundary_faces(mesh.tets(), &zone_tets[j])) c.elements_.push_back({{-1, f[0], f[1], f[2]}, j});
    c.rest_.push_back(v0);
  }
  c.finish(mesh.num_nodes(), dofs, pattern);
  return c;
}

VolumeConstraints VolumeConstraints::surface(const Mesh& mesh, const DofMap& dofs, const Pattern& pattern) {
  // The enclosed volume is the sum over outward triangles (a, b, c) of the signed volume of the
  // tet (origin, a, b, c): the divergence theorem. The origin (node -1) follows the body (origins()).
  VolumeConstraints c;
  for (const Tri& f : mesh.surface()) c.elements_.push_back({{-1, f[0], f[1], f[2]}, 0});
  c.rest_.push_back(surface_volume(mesh.rest_positions(), mesh.surface()));
  c.finish(mesh.num_nodes(), dofs, pattern);
  return c;
}

void VolumeConstraints::finish(int num_nodes, const DofMap& dofs, const Pattern& pattern) {
  dofs_ = dofs;
  auto dof = [&](int n, int d) { return 3 * static_cast<Index>(dofs.free_index[n]) + d; };
  auto is_free = [&](int n) { return n >= 0 && dofs.free_index[n] >= 0; };
  // Each constraint's boundary nodes (driven ones too), for the origin.
  boundary_nodes_.assign(rest_.size(), {});
  for (const Element& e : elements_)
    for (int n : e.nodes)
      if (n >= 0) boundary_nodes_[e.constraint].push_back(n);
  for (auto& b : boundary_nodes_) {
    std::sort(b.begin(), b.end());
    b.erase(std::unique(b.begin(), b.end()), b.end());
  }
  // Rows of G: the free dofs of every element's nodes.
  row_dofs_.assign(rest_.size(), {});
  for (const Element& e : elements_)
    for (int n : e.nodes)
      if (is_free(n))
        for (int d = 0; d < 3; ++d) row_dofs_[e.constraint].push_back(dof(n, d));
  for (auto& r : row_dofs_) {
    std::sort(r.begin(), r.end());
    r.erase(std::unique(r.begin(), r.end()), r.end());
  }
  std::vector<std::vector<int>> lists;
  for (const Element& e : elements_) {
    std::vector<int> l, rs(12, -1);
    const auto& r = row_dofs_[e.constraint];
    for (int k = 0; k < 4; ++k) {
      const int n = e.nodes[k];
      if (n >= 0) l.push_back(n);
      if (!is_free(n)) continue;
      for (int d = 0; d < 3; ++d)
        rs[3 * k + d] = static_cast<int>(std::lower_bound(r.begin(), r.end(), dof(n, d)) - r.begin());
    }
    lists.push_back(l);
    row_slot_.push_back(rs);
    // Hessian slots; the origin of a surface element has none (a stand-in node, then cleared).
    int nodes[4];
    for (int k = 0; k < 4; ++k) nodes[k] = e.nodes[k] < 0 ? e.nodes[1] : e.nodes[k];
    auto s = slot_map(pattern, dofs, nodes, 4);
    if (e.nodes[0] < 0)
      for (int a = 0; a < 12; ++a)
        for (int b = 0; b < 12; ++b)
          if (a < 3 || b < 3) s[a * 12 + b] = -1;
    slots_.insert(slots_.end(), s.begin(), s.end());
  }
  colours_ = colour_elements(num_nodes, lists);
}

void VolumeConstraints::volumes(const Points& x, Eigen::VectorXd& vol) const {
  vol.resize(size());
  sum_volumes(x, vol.data());
}

void VolumeConstraints::sum_volumes(const Points& x, double* vol) const {
  const std::vector<Vec3>& o = origins(x);
  for (int j = 0; j < size(); ++j) vol[j] = 0.0;
  for (const Element& e : elements_) vol[e.constraint] += tet_volume(element_x(x, e, o), nullptr, nullptr);
}

void VolumeConstraints::value(const Points& x, double* g) const {
  sum_volumes(x, g);
  for (int j = 0; j < size(); ++j) g[j] -= rest_[j] + (offset_.empty() ? 0.0 : offset_[j]);
}

void VolumeConstraints::restore_from(const Points& x0, double t0, double duration) {
  if (!(duration > 0)) throw Error("zones.restore_time: expected a duration > 0");
  start_offset_.assign(rest_.size(), 0.0);
  sum_volumes(x0, start_offset_.data());
  for (std::size_t j = 0; j < rest_.size(); ++j) start_offset_[j] -= rest_[j];
  restore_t0_ = t0;
  restore_duration_ = duration;
  set_time(t0);
}

void VolumeConstraints::set_time(double t) {
  if (start_offset_.empty()) return;
  const double s = std::clamp((t - restore_t0_) / restore_duration_, 0.0, 1.0);
  // remaining fraction 1 - p(s), p = 10s^3 - 15s^4 + 6s^5; dp/ds = 30 s^2 (1 - s)^2
  const double p = s * s * s * (10.0 + s * (-15.0 + 6.0 * s)),
               dp = 30.0 * s * s * (1.0 - s) * (1.0 - s) / restore_duration_;
  offset_.resize(rest_.size());
  rate_.resize(rest_.size());
  for (std::size_t j = 0; j < rest_.size(); ++j) {
    offset_[j] = start_offset_[j] * (1.0 - p);
    rate_[j] = -start_offset_[j] * dp;
  }
}

void VolumeConstraints::gradient(const Points& x, std::vector<double>* rows) const {
  const std::vector<Vec3>& o = origins(x);
  for (int j = 0; j < size(); ++j) rows[j].assign(row_dofs_[j].size(), 0.0);
  for (std::size_t i = 0; i < elements_.size(); ++i) {
    const Element& e = elements_[i];
    Vec12 g;
    tet_volume(element_x(x, e, o), &g, nullptr);
    for (int a = 0; a < 12; ++a)
      if (row_slot_[i][a] >= 0) rows[e.constraint][row_slot_[i][a]] += g[a];
  }
}

Eigen::VectorXd VolumeConstraints::full_gradient(const Points& x, int j) const {
  const std::vector<Vec3>& o = origins(x);
  Eigen::VectorXd out = Eigen::VectorXd::Zero(3 * x.cols());
  for (const Element& e : elements_) {
    if (e.constraint != j) continue;
    Vec12 g;
    tet_volume(element_x(x, e, o), &g, nullptr);
    for (int k = 0; k < 4; ++k)
      if (e.nodes[k] >= 0) out.segment<3>(3 * e.nodes[k]) += g.segment<3>(3 * k);
  }
  return out;
}

void VolumeConstraints::time_derivative(const Points& x, const Eigen::VectorXd& v, double* gt) const {
  const std::vector<Vec3>& o = origins(x);
  for (int j = 0; j < size(); ++j) gt[j] = 0.0;
  for (const Element& e : elements_) {
    bool driven = false;
    for (int n : e.nodes) driven |= n >= 0 && dofs_.free_index[n] < 0;
    if (!driven) continue;
    Vec12 g;
    tet_volume(element_x(x, e, o), &g, nullptr);
    for (int k = 0; k < 4; ++k)
      if (e.nodes[k] >= 0 && dofs_.free_index[e.nodes[k]] < 0)
        gt[e.constraint] += g.segment<3>(3 * k).dot(v.segment<3>(3 * e.nodes[k]));
  }
  for (std::size_t j = 0; j < rate_.size(); ++j) gt[j] -= rate_[j];
}

void VolumeConstraints::hessian_times(const Points& x, const Eigen::VectorXd& xdot, std::vector<double>* rows) const {
  const std::vector<Vec3>& o = origins(x);
  for (int j = 0; j < size(); ++j) rows[j].assign(row_dofs_[j].size(), 0.0);
  for (std::size_t i = 0; i < elements_.size(); ++i) {
    const Element& e = elements_[i];
    Mat12 H;
    tet_volume(element_x(x, e, o), nullptr, &H);
    Vec12 ve;
    for (int k = 0; k < 4; ++k)
      ve.segment<3>(3 * k) = e.nodes[k] < 0 ? Vec3::Zero() : Vec3(xdot.segment<3>(3 * e.nodes[k]));
    const Vec12 hv = H * ve;
    for (int a = 0; a < 12; ++a)
      if (row_slot_[i][a] >= 0) rows[e.constraint][row_slot_[i][a]] += hv[a];
  }
}

void VolumeConstraints::add_hessian(const Points& x, const double* lambda, double scale, double* values) const {
  const std::vector<Vec3>& o = origins(x);
  for_each_coloured(colours_, [&](int i) {
    const Element& e = elements_[i];
    const double w = scale * lambda[e.constraint];
    if (w == 0.0) return 0.0;
    Mat12 H;
    tet_volume(element_x(x, e, o), nullptr, &H);
    const Index* s = slots_.data() + 144 * static_cast<std::size_t>(i);
    for (int a = 0; a < 144; ++a)
      if (s[a] >= 0) values[s[a]] += w * H(a / 12, a % 12);
    return 0.0;
  });
}

void VolumeConstraints::add_pressure(const double* lambda, std::vector<double>& p) const {
  for (std::size_t j = 0; j < zone_tets_.size(); ++j)
    for (int e : zone_tets_[j]) p[e] -= lambda[j];
}

std::vector<std::vector<int>> ring_zones(const Mesh& mesh, int k, const DofMap& dofs) {
  std::vector<std::vector<int>> zones;
  for (int v = 0; v < mesh.num_nodes(); ++v)  // node order, whatever the order of the dofs
    if (dofs.free_index[v] >= 0) zones.push_back(mesh.tet_ring(v, k));
  return zones;
}

std::vector<std::vector<int>> patch_zones(const Mesh& mesh, int k) {
  const int N = mesh.num_nodes();
  const Adjacency& nb = mesh.node_nodes();
  std::vector<int> owner(N, -1), seeds;
  // Seeds: a node with no seed within 2k - 1 edges (near: distance to the nearest seed so far).
  std::vector<int> near(N, std::numeric_limits<int>::max());
  for (int v = 0; v < N; ++v) {
    if (near[v] < 2 * k) continue;
    seeds.push_back(v);
    std::vector<int> frontier{v};
    near[v] = 0;
    for (int d = 1; d < 2 * k && !frontier.empty(); ++d) {
      std::vector<int> next;
      for (int a : frontier)
        for (const int* b = nb.begin(a); b != nb.end(a); ++b)
          if (near[*b] > d) {
            near[*b] = d;
            next.push_back(*b);
          }
      frontier.swap(next);
    }
  }
  // Every node to its nearest seed: breadth first from all seeds at once.
  std::vector<int> frontier;
  for (std::size_t s = 0; s < seeds.size(); ++s) {
    owner[seeds[s]] = static_cast<int>(s);
    frontier.push_back(seeds[s]);
  }
  while (!frontier.empty()) {
    std::vector<int> next;
    for (int a : frontier)
      for (const int* b = nb.begin(a); b != nb.end(a); ++b)
        if (owner[*b] < 0) {
          owner[*b] = owner[a];
          next.push_back(*b);
        }
    frontier.swap(next);
  }
  std::vector<std::vector<int>> zones(seeds.size());
  for (int e = 0; e < mesh.num_tets(); ++e) {
    const Tet& t = mesh.tets()[e];
    zones[owner[*std::min_element(t.begin(), t.end())]].push_back(e);
  }
  std::erase_if(zones, [](const std::vector<int>& z) { return z.empty(); });
  return zones;
}

}  // namespace isochor
