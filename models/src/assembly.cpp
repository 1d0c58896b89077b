#include "isochor/models/assembly.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "isochor/base/error.hpp"

namespace isochor {

DofMap DofMap::make(int num_nodes, const std::vector<int>& dirichlet, const std::vector<int>& order) {
  if (!order.empty() && static_cast<int>(order.size()) != num_nodes)
    throw Error("dof map: the node order lists " + std::to_string(order.size()) + " nodes, the mesh has " +
                std::to_string(num_nodes));
  DofMap d;
  d.free_index.assign(num_nodes, 0);
  for (int v : dirichlet) d.free_index.at(v) = -1;
  std::vector<char> seen(order.empty() ? 0 : num_nodes, 0);
  for (int k = 0; k < num_nodes; ++k) {
    const int v = order.empty() ? k : order[k];
    if (!order.empty()) {
      if (v < 0 || v >= num_nodes || seen[v]) throw Error("dof map: the node order is not a permutation of the nodes");
      seen[v] = 1;
    }
    if (d.free_index[v] == 0) {
      d.free_index[v] = static_cast<int>(d.free_nodes.size());
      d.free_nodes.push_back(v);
    }
  }
  return d;
}

Pattern pattern_from_elements(const DofMap& dofs, const std::vector<std::vector<int>>& elements) {
  // Node graph of free nodes, then each node pair expands into a dense 3x3 block.
  const int nf = dofs.num_free();
  std::vector<std::vector<int>> nbr(nf);
  for (const auto& el : elements)
    for (int a : el) {
      const int fa = dofs.free_index[a];
      if (fa < 0) continue;
      for (int b : el) {
        const int fb = dofs.free_index[b];
        if (fb >= 0) nbr[fa].push_back(fb);
      }
    }
  Pattern p;
  p.n = 3 * static_cast<Index>(nf);
  p.col_ptr.assign(p.n + 1, 0);
  for (int f = 0; f < nf; ++f) {
    auto& list = nbr[f];
    if (list.empty()) list.push_back(f);  // a free node in no element still has its diagonal
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  for (int f = 0; f < nf; ++f)
    for (int d = 0; d < 3; ++d) p.col_ptr[3 * f + d + 1] = p.col_ptr[3 * f + d] + 3 * static_cast<Index>(nbr[f].size());
  p.row_ind.resize(p.col_ptr.back());
  for (int f = 0; f < nf; ++f)
    for (int d = 0; d < 3; ++d) {
      Index k = p.col_ptr[3 * f + d];
      for (int g : nbr[f])
        for (int e = 0; e < 3; ++e) p.row_ind[k++] = 3 * static_cast<Index>(g) + e;
    }
  return p;
}

std::vector<Index> slot_map(const Pattern& p, const DofMap& dofs, const int* nodes, int k) {
  const int n = 3 * k;
  std::vector<Index> s(n * n, -1);
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) {
      const int fa = dofs.free_index[nodes[a / 3]], fb = dofs.free_index[nodes[b / 3]];
      if (fa < 0 || fb < 0) continue;
      // Local entry (a, b) = row a, column b.
      s[a * n + b] = p.find(3 * static_cast<Index>(fa) + a % 3, 3 * static_cast<Index>(fb) + b % 3);
    }
  return s;
}

namespace {
// Interleaves the low 21 bits of x, y, z (Morton code).
std::uint64_t morton(std::uint64_t x, std::uint64_t y, std::uint64_t z) {
  auto spread = [](std::uint64_t v) {
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffULL;
    v = (v | v << 16) & 0x1f0000ff0000ffULL;
    v = (v | v << 8) & 0x100f00f00f00f00fULL;
    v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
    v = (v | v << 2) & 0x1249249249249249ULL;
    return v;
  };
  return spread(x) | spread(y) << 1 | spread(z) << 2;
}
}  // namespace

std::vector<int> morton_order(const Points& points) {
  const int N = static_cast<int>(points.cols());
  std::vector<int> order(N);
  for (int e = 0; e < N; ++e) order[e] = e;
  if (N == 0) return order;
  const Vec3 lo = points.rowwise().minCoeff(), hi = points.rowwise().maxCoeff();
  const Vec3 scale = ((hi - lo).array().max(1e-300).inverse() * double((1 << 21) - 1)).matrix();
  std::vector<std::uint64_t> key(N);
  for (int e = 0; e < N; ++e) {
    const Vec3 u = (points.col(e) - lo).cwiseProduct(scale);
    key[e] =
        morton(static_cast<std::uint64_t>(u.x()), static_cast<std::uint64_t>(u.y()), static_cast<std::uint64_t>(u.z()));
  }
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return key[a] < key[b]; });
  return order;
}

ElementSchedule colour_elements(int num_nodes, const std::vector<std::vector<int>>& elements, const Points* centroids,
                                int chunk) {
  ElementSchedule s;
  const int E = static_cast<int>(elements.size());
  if (centroids) {
    s.order = morton_order(*centroids);
  } else {
    s.order.resize(E);
    for (int e = 0; e < E; ++e) s.order[e] = e;
  }
  // Without a spatial order, chunks of one element (the plain element colouring); small meshes:
  // chunks small enough that each colour still has work for every thread.
  chunk = centroids ? std::max(1, std::min(chunk, E / 64)) : 1;
  for (int k = 0; k < E; k += chunk) s.chunk_start.push_back(k);
  s.chunk_start.push_back(E);
  const int C = static_cast<int>(s.chunk_start.size()) - 1;
  std::vector<std::vector<int>> node_colours(num_nodes);
  std::vector<char> used;
  for (int c = 0; c < C; ++c) {
    used.assign(s.colours.size() + 1, 0);
    for (int k = s.chunk_start[c]; k < s.chunk_start[c + 1]; ++k)
      for (int v : elements[s.order[k]])
        for (int col : node_colours[v]) used[col] = 1;
    int col = 0;
    while (used[col]) ++col;
    if (col == static_cast<int>(s.colours.size())) s.colours.emplace_back();
    s.colours[col].push_back(c);
    for (int k = s.chunk_start[c]; k < s.chunk_start[c + 1]; ++k)
      for (int v : elements[s.order[k]])
        if (node_colours[v].empty() || node_colours[v].back() != col) node_colours[v].push_back(col);
  }
  return s;
}

Eigen::VectorXd lumped_mass(const Mesh& mesh, double density, const std::vector<double>* tet_density) {
  Eigen::VectorXd m = Eigen::VectorXd::Zero(mesh.num_nodes());
  for (int e = 0; e < mesh.num_tets(); ++e)
    for (int v : mesh.tets()[e]) m[v] += (tet_density ? (*tet_density)[e] : density) * mesh.rest_volumes()[e] / 4.0;
  return m;
}

Eigen::VectorXd surface_areas(const Mesh& mesh) {
  Eigen::VectorXd a = Eigen::VectorXd::Zero(mesh.num_nodes());
  const Points& X = mesh.rest_positions();
  for (const Tri& t : mesh.surface()) {
    const double area = 0.5 * (X.col(t[1]) - X.col(t[0])).cross(X.col(t[2]) - X.col(t[0])).norm();
    for (int v : t) a[v] += area / 3.0;
  }
  return a;
}

namespace {
Vec9n gather_tri(const Points& x, const Tri& t) {
  Vec9n v;
  for (int k = 0; k < 3; ++k) v.segment<3>(3 * k) = x.col(t[k]);
  return v;
}
}  // namespace

ElasticAssembly::ElasticAssembly(const Mesh& mesh, std::shared_ptr<const Material> material, const DofMap& dofs,
                                 EpidermisSpec epidermis)
    : mesh_(mesh), material_(std::move(material)), dofs_(dofs), epi_(epidermis) {
  const auto& X = mesh.rest_positions();
  const int T = mesh.num_tets();
  std::vector<std::vector<int>> tets(T), tris;
  Points centres(3, T);
  for (int e = 0; e < T; ++e) {
    tets[e].assign(mesh.tets()[e].begin(), mesh.tets()[e].end());
    centres.col(e) = gather(X, mesh.tets()[e]).reshaped(3, 4).rowwise().mean();
  }
  if (epi_.lambda_e > 0)
    for (const Tri& f : mesh.surface()) {
      tris.emplace_back(f.begin(), f.end());
      tri_area_.push_back(triangle_area(gather_tri(X, f), nullptr, nullptr));
    }
  pattern_ = pattern_from_elements(dofs_, tets);  // surface triangles couple only tet neighbours
  tet_colours_ = colour_elements(mesh.num_nodes(), tets, &centres);
  tri_colours_ = colour_elements(mesh.num_nodes(), tris);
  // Each tet's data stored at its position in the pass's order, so that a pass reads it in
  // sequence.
  tets_.resize(T);
  shapes_.resize(T);
  tet_slots_.resize(144 * static_cast<std::size_t>(T));
  for (int k = 0; k < T; ++k) {
    const int e = tet_colours_.order[k];
    const Tet& t = mesh.tets()[e];
    tets_[k] = t;
    shapes_[k] = TetShape::make(X.col(t[0]), X.col(t[1]), X.col(t[2]), X.col(t[3]));
    auto sl = slot_map(pattern_, dofs_, tets[e].data(), 4);
    std::copy(sl.begin(), sl.end(), tet_slots_.begin() + 144 * static_cast<std::size_t>(k));
  }
  tri_slots_.resize(81 * tris.size());
  for (std::size_t f = 0; f < tris.size(); ++f) {
    auto s = slot_map(pattern_, dofs_, tris[f].data(), 3);
    std::copy(s.begin(), s.end(), tri_slots_.begin() + 81 * f);
  }
}

double ElasticAssembly::energy(const Points& x) const {
  double E = 0.0;
  const int T = mesh_.num_tets();
#pragma omp parallel for reduction(+ : E) schedule(static)
  for (int k = 0; k < T; ++k) {
    if (tet_counted(k, 1.0) == 0.0) continue;
    const Vec12 xe = gather(x, tets_[k]);
    E += tet_energy(material_at(k), shapes_[k], xe, nullptr, nullptr) +
         fibre_term(k, xe, nullptr, nullptr, nullptr, nullptr);
  }
  const int S = static_cast<int>(tri_area_.size());
  for (int f = 0; f < S; ++f)
    if (tri_counted(f, 1.0) != 0.0)
      E += epidermis_energy(tri_area_[f], epi_.lambda_e, epi_.gamma, gather_tri(x, mesh_.surface()[f]), nullptr,
                            nullptr);
  return E;
}

namespace {
// values[s] += scale * H for every local entry with a slot (and the same into values2).
template <int N>
void scatter(const Eigen::Matrix<double, N, N>& H, const Index* slots, double scale, double* values, double scale2,
             double* values2) {
  for (int a = 0; a < N; ++a)
    for (int b = 0; b < N; ++b) {
      const Index s = slots[a * N + b];
      if (s < 0) continue;
      values[s] += scale * H(a, b);
      if (values2) values2[s] += scale2 * H(a, b);
    }
}

// H := its projection onto the positive semi-definite matrices (the nearest in the Frobenius
// norm): negative eigenvalues set to zero. A matrix already semi-definite is left as it is.
template <int N>
void project_psd(Eigen::Matrix<double, N, N>& H) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> eig(H);
  const auto& l = eig.eigenvalues();
  if (l.minCoeff() >= 0) return;
  const auto& V = eig.eigenvectors();
  H = V * l.cwiseMax(0.0).asDiagonal() * V.transpose();
}

// One element's share of an ElementPass, for elements of N nodes. eval(g, H, d, Hd) computes
// the energy and, when asked, its gradient g, Hessian H and H d.
template <int N, class Nodes, class Eval>
double element_pass(const ElementPass& p, const Nodes& nodes, const Index* slots, Eval&& eval) {
  constexpr int D = 3 * N;
  using Vec = Eigen::Matrix<double, D, 1>;
  Vec g, ve, Hv;
  Eigen::Matrix<double, D, D> H;
  const bool hess = p.values || p.values2;
  if (p.Kv)
    for (int k = 0; k < N; ++k) ve.template segment<3>(3 * k) = p.v->template segment<3>(3 * nodes[k]);
  const double E = eval(p.grad ? &g : nullptr, hess ? &H : nullptr, p.Kv ? &ve : nullptr, p.Kv ? &Hv : nullptr);
  if (p.grad)
    for (int k = 0; k < N; ++k) p.grad->template segment<3>(3 * nodes[k]) += g.template segment<3>(3 * k);
  if (hess && p.project) project_psd(H);
  if (p.values)
    scatter<D>(H, slots, p.scale, p.values, p.scale2, p.values2);
  else if (p.values2)
    scatter<D>(H, slots, p.scale2, p.values2, 0.0, nullptr);
  if (p.Kv)
    for (int k = 0; k < N; ++k) p.Kv->template segment<3>(3 * nodes[k]) += p.v_scale * Hv.template segment<3>(3 * k);
  return E;
}
}  // namespace

double ElasticAssembly::evaluate(const Points& x, const ElementPass& p) const {
  // The gradient alone (every residual of an implicit integrator): one lean pass, the general
  // path's formulas without its 12- and 9-vectors: P = 2 W_I F + W_J cof F, node a gets V P b_a.
  const bool gradient_only = p.grad && !p.values && !p.values2 && !p.Kv;
  const double tets =
      gradient_only
          ? for_each_coloured(tet_colours_,
                              [&](int e) {
                                if (skip_tet(e)) return 0.0;
                                const Tet& t = tets_[e];
                                const TetShape& s = shapes_[e];
                                const Vec3 x0 = x.col(t[0]);
                                Mat3 Ds;
                                Ds << x.col(t[1]) - x0, x.col(t[2]) - x0, x.col(t[3]) - x0;
                                const Mat3 F = Ds * s.Dm_inv;
                                const Mat3 C = cofactor(F);
                                const InvariantDerivatives w =
                                    material_at(e).first_invariants(F.squaredNorm(), F.col(0).dot(C.col(0)));
                                Mat3 P = (2.0 * w.W_I) * F + w.W_J * C;
                                double psi = w.W;
                                if (has_fibres()) add_fibre_stress(e, F, P, psi);
                                const Mat3 G = s.rest_volume * (P * s.Dm_inv.transpose());
                                Eigen::VectorXd& g = *p.grad;
                                g.segment<3>(3 * static_cast<Index>(t[0])) -= G.col(0) + G.col(1) + G.col(2);
                                for (int k = 1; k < 4; ++k) g.segment<3>(3 * static_cast<Index>(t[k])) += G.col(k - 1);
                                return tet_counted(e, s.rest_volume * psi);
                              })
          : for_each_coloured(tet_colours_, [&](int e) {
              if (skip_tet(e)) return 0.0;
              const Tet& t = tets_[e];
              return tet_counted(e, element_pass<4>(p, t, tet_slots_.data() + 144 * static_cast<std::size_t>(e),
                                                    [&](Vec12* g, Mat12* H, const Vec12* d, Vec12* Hd) {
                                                      const Vec12 xe = gather(x, t);
                                                      return tet_energy(material_at(e), shapes_[e], xe, g, H, d, Hd) +
                                                             fibre_term(e, xe, g, H, d, Hd);
                                                    }));
            });
  const double tris = for_each_coloured(tri_colours_, [&](int f) {
    if (skip_tri(f)) return 0.0;
    const Tri& t = mesh_.surface()[f];
    return tri_counted(f, element_pass<3>(p, t, tri_slots_.data() + 81 * static_cast<std::size_t>(f),
                                          [&](Vec9n* g, Mat9n* H, const Vec9n* d, Vec9n* Hd) {
                                            Mat9n Hl;
                                            Mat9n* Hp = H ? H : (Hd ? &Hl : nullptr);
                                            const double E = epidermis_energy(tri_area_[f], epi_.lambda_e, epi_.gamma,
                                                                              gather_tri(x, t), g, Hp);
                                            if (Hd) *Hd = *Hp * *d;
                                            return E;
                                          }));
  });
  return tets + tris;
}

double ElasticAssembly::gradient(const Points& x, Eigen::VectorXd& grad) const {
  grad.setZero(3 * x.cols());
  ElementPass p;
  p.grad = &grad;
  return evaluate(x, p);
}

void ElasticAssembly::add_hessian(const Points& x, double scale, double* values, double scale2, double* values2,
                                  bool project) const {
  ElementPass p;
  p.project = project;
  p.values = values;
  p.scale = scale;
  p.values2 = values2;
  p.scale2 = scale2;
  evaluate(x, p);
}

void ElasticAssembly::add_hessian_times(const Points& x, const Eigen::VectorXd& v, double scale,
                                        Eigen::VectorXd& out) const {
  ElementPass p;
  p.v = &v;
  p.v_scale = scale;
  p.Kv = &out;
  evaluate(x, p);
}

void ElasticAssembly::pressures(const Points& x, std::vector<double>& p) const {
  p.resize(mesh_.num_tets());
  const int T = mesh_.num_tets();
#pragma omp parallel for schedule(static)
  for (int k = 0; k < T; ++k) {
    const Mat3 F = shapes_[k].F(gather(x, tets_[k]));
    double& pk = p[tet_colours_.order[k]] = material_at(k).pressure(F);
    // A fibre's stress adds -tr(sigma_f) / 3 = -tr(P_f F^T) / (3 J).
    if (has_fibres() && fibre_muscle_[k] >= 0) {
      Mat3 P = Mat3::Zero();
      double psi = 0;
      add_fibre_stress(k, F, P, psi);
      pk -= (P * F.transpose()).trace() / (3.0 * F.determinant());
    }
  }
}

void ElasticAssembly::set_tet_materials(std::vector<std::shared_ptr<const Material>> materials,
                                        const std::vector<int>& material_of) {
  const int T = mesh_.num_tets();
  if (materials.empty()) {
    materials_.clear();
    tet_material_.clear();
    return;
  }
  if (static_cast<int>(material_of.size()) != T)
    throw Error("tet materials: expected one index per tet (" + std::to_string(T) + ")");
  tet_material_.resize(T);
  for (int k = 0; k < T; ++k) {
    const int e = tet_colours_.order[k], m = material_of[e];
    if (m < 0 || m >= static_cast<int>(materials.size()))
      throw Error("tet materials: tet " + std::to_string(e) + " names material " + std::to_string(m) + " of " +
                  std::to_string(materials.size()));
    tet_material_[k] = m;
  }
  materials_ = std::move(materials);
}

void ElasticAssembly::set_fibres(const FibreField& field) {
  const int T = mesh_.num_tets();
  if (field.empty()) {
    muscles_.clear();
    activation_.clear();
    fibre_muscle_.clear();
    fibre_dir_.clear();
    return;
  }
  if (static_cast<int>(field.muscle_of.size()) != T || static_cast<int>(field.direction.size()) != T)
    throw Error("fibre field: expected a muscle index and a direction per tet (" + std::to_string(T) + ")");
  muscles_ = field.muscles;
  activation_.assign(muscles_.size(), 0.0);
  fibre_muscle_.resize(T);
  fibre_dir_.resize(T);
  for (int k = 0; k < T; ++k) {
    const int e = tet_colours_.order[k];
    fibre_muscle_[k] = field.muscle_of[e];
    fibre_dir_[k] = field.direction[e];
    if (fibre_muscle_[k] >= static_cast<int>(muscles_.size()))
      throw Error("fibre field: tet " + std::to_string(e) + " names muscle " + std::to_string(fibre_muscle_[k]) +
                  " of " + std::to_string(muscles_.size()));
  }
}

void ElasticAssembly::set_activations(const std::vector<double>& activation) {
  if (activation.size() != muscles_.size())
    throw Error("activations: expected " + std::to_string(muscles_.size()) + " (one per muscle), got " +
                std::to_string(activation.size()));
  activation_ = activation;
}

double ElasticAssembly::fibre_term(int k, const Vec12& x, Vec12* grad, Mat12* hess, const Vec12* dir,
                                   Vec12* hess_dir) const {
  if (!has_fibres() || fibre_muscle_[k] < 0) return 0.0;
  const int m = fibre_muscle_[k];
  Vec12 g, Hd;
  Mat12 H;
  const double E = fibre_tet_energy(muscles_[m], activation_[m], fibre_dir_[k], shapes_[k], x, grad ? &g : nullptr,
                                    hess ? &H : nullptr, dir, hess_dir ? &Hd : nullptr);
  if (grad) *grad += g;
  if (hess) *hess += H;
  if (hess_dir) *hess_dir += Hd;
  return E;
}

void ElasticAssembly::add_fibre_stress(int k, const Mat3& F, Mat3& P, double& psi) const {
  const int m = fibre_muscle_[k];
  if (m < 0) return;
  double fibre_psi = 0;
  P += fibre_stress_tensor(muscles_[m], activation_[m], fibre_dir_[k], F, &fibre_psi);
  psi += fibre_psi;
}

void ElasticAssembly::keep_rank(const std::vector<int>& node_rank, int rank) {
  auto mark = [&](const int* nodes, int k, char& here, char& counted) {
    const int lowest = *std::min_element(nodes, nodes + k);
    counted = node_rank[lowest] == rank;
    here = counted;
    for (int a = 0; a < k; ++a) here |= dofs_.free_index[nodes[a]] >= 0 && node_rank[nodes[a]] == rank;
  };
  const int T = mesh_.num_tets(), S = static_cast<int>(tri_area_.size());
  tet_here_.resize(T), tet_counted_.resize(T), tri_here_.resize(S), tri_counted_.resize(S);
  for (int k = 0; k < T; ++k) mark(tets_[k].data(), 4, tet_here_[k], tet_counted_[k]);
  for (int f = 0; f < S; ++f) mark(mesh_.surface()[f].data(), 3, tri_here_[f], tri_counted_[f]);
}

int ElasticAssembly::inverted_tets(const Points& x) const {
  int n = 0;
  for (const Tet& t : mesh_.tets()) n += tet_signed_volume(x.col(t[0]), x.col(t[1]), x.col(t[2]), x.col(t[3])) <= 0;
  return n;
}

}  // namespace isochor
