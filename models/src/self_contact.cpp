#include "isochor/self_contact.hpp"

#include <nanoflann.hpp>

#include <cmath>
#include <limits>

#include "isochor/elements.hpp"
#include "isochor/paint.hpp"

namespace isochor {

namespace {
using KdTree = nanoflann::KDTreeEigenMatrixAdaptor<Points, 3, nanoflann::metric_L2_Simple, false>;

}  // namespace

SelfContact::SelfContact(const Mesh& mesh, const ContactLaw& law, double exclude, const DofMap& dofs, const Pattern& pattern,
                         Eigen::VectorXd area)
    : mesh_(mesh), law_(law), exclude2_(exclude * exclude), dofs_(dofs), area_(std::move(area)) {
  diag_slots_.resize(9 * static_cast<std::size_t>(dofs.num_free()));
  for (int f = 0; f < dofs.num_free(); ++f)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) diag_slots_[9 * f + 3 * a + b] = pattern.find(3 * Index(f) + a, 3 * Index(f) + b);
  const Points& X = mesh.rest_positions();
  for (const Tri& t : mesh.surface()) {
    const Vec3 c = (X.col(t[0]) + X.col(t[1]) + X.col(t[2])) / 3.0;
    for (int v : t) reach_ = std::max(reach_, (X.col(v) - c).norm());
  }
}

SelfContact::~SelfContact() = default;

std::vector<SelfContact::Pair> SelfContact::pairs(const Points& x) const {
  const auto& S = mesh_.surface();
  const Points& X = mesh_.rest_positions();
  Points centroid(3, static_cast<Eigen::Index>(S.size()));
  double reach = 0;  // now: triangles stretch
  for (std::size_t f = 0; f < S.size(); ++f) {
    centroid.col(f) = (x.col(S[f][0]) + x.col(S[f][1]) + x.col(S[f][2])) / 3.0;
    for (int v : S[f]) reach = std::max(reach, (x.col(v) - centroid.col(f)).norm());
  }
  KdTree tree(3, std::cref(centroid), 10);
  const double r = law_.thickness + reach;
  std::vector<Pair> out;
  std::vector<std::pair<Eigen::Index, double>> found;
  for (int p : mesh_.surface_nodes()) {
    found.clear();
    tree.index->radiusSearch(x.col(p).data(), r * r, found, nanoflann::SearchParams(32, 0, false));
    Pair best{p, {}, Vec3::Zero(), Vec3::Zero(), law_.thickness};
    bool any = false;
    for (const auto& item : found) {
      const Tri& t = S[static_cast<std::size_t>(item.first)];
      bool near = false;  // the node's own neighbourhood at rest
      for (int v : t) near = near || (X.col(v) - X.col(p)).squaredNorm() < exclude2_;
      if (near) continue;
      const Vec3 q = closest_on_triangle(x.col(p), x.col(t[0]), x.col(t[1]), x.col(t[2]));
      const double d = (x.col(p) - q).norm();
      if (d < best.d && d > 0) {
        best = {p, t, barycentric(q, x.col(t[0]), x.col(t[1]), x.col(t[2])), (x.col(p) - q) / d, d};
        any = true;
      }
    }
    if (any) out.push_back(best);
  }
  return out;
}

double SelfContact::add_gradient(const Points& x, Eigen::VectorXd& grad) const {
  double E = 0;
  for (const Pair& c : pairs(x)) {
    const double k = law_.per_area ? law_.stiffness * area_[c.node] : law_.stiffness, p = law_.thickness - c.d;
    E += k / 3.0 * p * p * p;
    // dE/dd = -k p^2; dd/dx_node = n, dd/dx_corner_i = -w_i n.
    grad.segment<3>(3 * c.node) -= k * p * p * c.n;
    for (int i = 0; i < 3; ++i) grad.segment<3>(3 * c.tri[i]) += k * p * p * c.weights[i] * c.n;
  }
  return E;
}

void SelfContact::add_forces(const Points& x, const Eigen::VectorXd* xdot, Points& out) const {
  Eigen::VectorXd g = Eigen::VectorXd::Zero(x.size());
  add_gradient(x, g);
  if (xdot) add_damping(x, *xdot, g);
  out -= Eigen::Map<const Points>(g.data(), 3, x.cols());
}

void SelfContact::add_hessian(const Points& x, double scale, double* values) const {
  auto add = [&](int node, double w2, double k, double p, const Vec3& n) {
    const int f = dofs_.free_index[node];
    if (f < 0) return;
    const Mat3 H = scale * 2.0 * k * p * w2 * n * n.transpose();
    for (int e = 0; e < 9; ++e) values[diag_slots_[9 * f + e]] += H(e / 3, e % 3);
  };
  for (const Pair& c : pairs(x)) {
    const double k = law_.per_area ? law_.stiffness * area_[c.node] : law_.stiffness, p = law_.thickness - c.d;
    add(c.node, 1.0, k, p, c.n);
    for (int i = 0; i < 3; ++i) add(c.tri[i], c.weights[i] * c.weights[i], k, p, c.n);
  }
}

void SelfContact::add_damping(const Points& x, const Eigen::VectorXd& xdot, Eigen::VectorXd& grad) const {
  if (law_.damping <= 0) return;
  for (const Pair& c : pairs(x)) {
    const double k = law_.per_area ? law_.stiffness * area_[c.node] : law_.stiffness, p = law_.thickness - c.d;
    Vec3 v = xdot.segment<3>(3 * c.node);
    for (int i = 0; i < 3; ++i) v -= c.weights[i] * xdot.segment<3>(3 * c.tri[i]);
    const Vec3 f = -k * law_.damping * p * p * c.n.dot(v) * c.n;  // on the node
    grad.segment<3>(3 * c.node) -= f;
    for (int i = 0; i < 3; ++i) grad.segment<3>(3 * c.tri[i]) += c.weights[i] * f;
  }
}

void SelfContact::add_damping_jacobian(const Points& x, double* neg_dfdv) const {
  if (law_.damping <= 0 || !neg_dfdv) return;
  for (const Pair& c : pairs(x)) {
    const double k = law_.per_area ? law_.stiffness * area_[c.node] : law_.stiffness, p = law_.thickness - c.d;
    auto add = [&](int node, double w2) {
      const int f = dofs_.free_index[node];
      if (f < 0) return;
      const Mat3 D = k * law_.damping * p * p * w2 * c.n * c.n.transpose();
      for (int e = 0; e < 9; ++e) neg_dfdv[diag_slots_[9 * f + e]] += D(e / 3, e % 3);
    };
    add(c.node, 1.0);
    for (int i = 0; i < 3; ++i) add(c.tri[i], c.weights[i] * c.weights[i]);
  }
}

double SelfContact::closest(const Points& x) const {
  double d = std::numeric_limits<double>::infinity();
  for (const Pair& c : pairs(x)) d = std::min(d, c.d);
  return d;
}

}  // namespace isochor
