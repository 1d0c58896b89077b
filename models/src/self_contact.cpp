#include "isochor/models/self_contact.hpp"

#include <nanoflann.hpp>

#include <algorithm>
#include <cmath>

#include "isochor/models/elements.hpp"
#include "isochor/core/paint.hpp"

namespace isochor {

namespace {
using KdTree = nanoflann::KDTreeEigenMatrixAdaptor<Points, 3, nanoflann::metric_L2_Simple, false>;

}  // namespace

SelfContact::SelfContact(const Mesh& mesh, const ContactLaw& law, double exclude, const DofMap& dofs,
                         const Pattern& pattern, Eigen::VectorXd area, double smoothing)
    : mesh_(mesh),
      law_(law),
      exclude2_(exclude * exclude),
      dofs_(dofs),
      area_(std::move(area)),
      tau_(smoothing > 0 ? smoothing : 0.1 * law.thickness) {
  surface_index_.assign(mesh.num_nodes(), -1);
  const std::vector<int>& nodes = mesh.surface_nodes();
  for (std::size_t i = 0; i < nodes.size(); ++i) surface_index_[nodes[i]] = static_cast<int>(i);
  diag_slots_.resize(9 * static_cast<std::size_t>(dofs.num_free()));
  for (int f = 0; f < dofs.num_free(); ++f)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) diag_slots_[9 * f + 3 * a + b] = pattern.find(3 * Index(f) + a, 3 * Index(f) + b);
}

SelfContact::~SelfContact() = default;

namespace {
// The Hessian of the distance from p to its closest point q on the triangle (a, b, c), with
// respect to p: 0 in the face's region, (I - e e^T - n n^T) / d beside an edge e, (I - n n^T) / d
// at a corner.
Mat3 distance_hessian(const Vec3& p, const Vec3& q, const Vec3& w, const Vec3* corner[3]) {
  const double d = (p - q).norm();
  const Vec3 n = (p - q) / d;
  const double eps = 1e-12;
  int zeros = 0, zero = -1;
  for (int i = 0; i < 3; ++i)
    if (w[i] < eps) ++zeros, zero = i;
  if (zeros == 0) return Mat3::Zero();
  Mat3 H = Mat3::Identity() - n * n.transpose();
  if (zeros == 1) {
    const Vec3 e = (*corner[(zero + 2) % 3] - *corner[(zero + 1) % 3]).normalized();
    H -= e * e.transpose();
  }
  return H / d;
}
}  // namespace

// The candidates: for each triangle, the surface nodes (not near it at rest) within the cutoff
// plus a skin of it, found at the positions `ref_` with a k-d tree. A node's distance to a
// triangle changes by at most its own move plus the farthest corner's, so while no surface node
// has moved more than half the skin since, every pair within the cutoff is among them: the tree is
// built again only then (a Verlet list), not for each configuration a residual asks about. Each
// triangle searches within the cutoff and skin plus its own reach (its corners' farthest from its
// centroid), so that one large triangle does not widen every search.
void SelfContact::find_candidates(const Points& xs, double radius) const {
  const auto& S = mesh_.surface();
  const Points& X = mesh_.rest_positions();
  const std::vector<int>& nodes = mesh_.surface_nodes();
  KdTree tree(3, std::cref(xs), 10);
  candidates_.assign(S.size(), {});
  std::vector<std::pair<Eigen::Index, double>> found;
  for (std::size_t f = 0; f < S.size(); ++f) {
    const Tri& t = S[f];
    const Vec3 a = xs.col(surface_index_[t[0]]), b = xs.col(surface_index_[t[1]]), cc = xs.col(surface_index_[t[2]]);
    const Vec3 centroid = (a + b + cc) / 3.0;
    const double reach = std::max({(a - centroid).norm(), (b - centroid).norm(), (cc - centroid).norm()});
    const double r = radius + reach;
    found.clear();
    tree.index->radiusSearch(centroid.data(), r * r, found, nanoflann::SearchParams(32, 0, false));
    for (const auto& item : found) {
      const int i = static_cast<int>(item.first), p = nodes[static_cast<std::size_t>(i)];
      bool near = false;  // the node's own neighbourhood at rest
      for (int v : t) near = near || (X.col(v) - X.col(p)).squaredNorm() < exclude2_;
      if (!near && (xs.col(i) - closest_on_triangle(xs.col(i), a, b, cc)).norm() < radius) candidates_[f].push_back(i);
    }
  }
  ref_ = xs;
}

const std::vector<SelfContact::Pair>& SelfContact::pairs(const Points& x) const {
  if (cached_x_.cols() == x.cols() && cached_x_ == x) return cached_;
  const auto& S = mesh_.surface();
  const std::vector<int>& nodes = mesh_.surface_nodes();
  Points xs(3, static_cast<Eigen::Index>(nodes.size()));
  for (std::size_t i = 0; i < nodes.size(); ++i) xs.col(static_cast<Eigen::Index>(i)) = x.col(nodes[i]);
  // Triangles farther than delta + 12 tau weigh less than e^-12 in the smoothed minimum of a node
  // in contact: they are left out.
  const double cutoff = law_.thickness + 12 * tau_, skin = cutoff;
  if (ref_.cols() != xs.cols() || (xs - ref_).colwise().norm().maxCoeff() > 0.5 * skin)
    find_candidates(xs, cutoff + skin);
  std::vector<std::vector<Term>> terms(nodes.size());
  for (std::size_t f = 0; f < S.size(); ++f) {
    const Tri& t = S[f];
    const Vec3 a = x.col(t[0]), b = x.col(t[1]), cc = x.col(t[2]);
    for (int i : candidates_[f]) {
      const int p = nodes[static_cast<std::size_t>(i)];
      const Vec3 q = closest_on_triangle(x.col(p), a, b, cc);
      const double d = (x.col(p) - q).norm();
      if (d >= cutoff || !(d > 0)) continue;
      const Vec3 w = barycentric(q, a, b, cc);
      const Vec3* corner[3] = {&a, &b, &cc};
      terms[static_cast<std::size_t>(i)].push_back(
          {t, w, (x.col(p) - q) / d, d, 0.0, distance_hessian(x.col(p), q, w, corner)});
    }
  }
  std::vector<Pair> out;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    if (terms[i].empty()) continue;
    Pair c{nodes[i], 0.0, Vec3::Zero(), std::move(terms[i])};
    double dmin = cutoff, sum = 0;
    for (const Term& t : c.terms) dmin = std::min(dmin, t.d);
    for (Term& t : c.terms) sum += t.omega = std::exp(-(t.d - dmin) / tau_);
    c.d = dmin - tau_ * std::log(sum);
    if (c.d >= law_.thickness) continue;
    for (Term& t : c.terms) {
      t.omega /= sum;
      c.n += t.omega * t.n;
    }
    out.push_back(std::move(c));
  }
  cached_x_ = x;
  cached_ = std::move(out);
  return cached_;
}

double SelfContact::add_gradient(const Points& x, Eigen::VectorXd& grad) const {
  double E = 0;
  for (const Pair& c : pairs(x)) {
    const double k = law_.per_area ? law_.stiffness * area_[c.node] : law_.stiffness, p = law_.thickness - c.d;
    E += k / 3.0 * p * p * p;
    // dE/dd = -k p^2; dd/dx_node = sum omega_i n_i, dd/dx_corner_j of triangle i = -omega_i w_ij n_i.
    grad.segment<3>(3 * c.node) -= k * p * p * c.n;
    for (const Term& t : c.terms)
      for (int j = 0; j < 3; ++j) grad.segment<3>(3 * t.tri[j]) += k * p * p * t.omega * t.weights[j] * t.n;
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
  auto add = [&](int node, const Mat3& H) {
    const int f = dofs_.free_index[node];
    if (f < 0) return;
    for (int e = 0; e < 9; ++e) values[diag_slots_[9 * f + e]] += scale * H(e / 3, e % 3);
  };
  for (const Pair& c : pairs(x)) {
    const double k = law_.per_area ? law_.stiffness * area_[c.node] : law_.stiffness, p = law_.thickness - c.d;
    // The node's block, exact: 2 k p g g^T - k p^2 d2s, with the smoothed minimum's
    // d2s = sum omega_i H_i - (sum omega_i n_i n_i^T - g g^T) / tau.
    Mat3 d2s = c.n * c.n.transpose() / tau_;
    for (const Term& t : c.terms) d2s += t.omega * (t.H - t.n * t.n.transpose() / tau_);
    add(c.node, 2.0 * k * p * c.n * c.n.transpose() - k * p * p * d2s);
    for (const Term& t : c.terms)  // the corners': Gauss-Newton
      for (int j = 0; j < 3; ++j) {
        const double w = t.omega * t.weights[j];
        add(t.tri[j], 2.0 * k * p * w * w * t.n * t.n.transpose());
      }
  }
}

void SelfContact::add_damping(const Points& x, const Eigen::VectorXd& xdot, Eigen::VectorXd& grad) const {
  if (law_.damping <= 0) return;
  for (const Pair& c : pairs(x)) {
    const double k = law_.per_area ? law_.stiffness * area_[c.node] : law_.stiffness, p = law_.thickness - c.d;
    // The approach rate: sdot = g . v_node - sum_i omega_i n_i . sum_j w_ij v_corner_ij.
    double sdot = c.n.dot(xdot.segment<3>(3 * c.node));
    for (const Term& t : c.terms)
      for (int j = 0; j < 3; ++j) sdot -= t.omega * t.weights[j] * t.n.dot(xdot.segment<3>(3 * t.tri[j]));
    const double m = k * law_.damping * p * p * sdot;  // the force is -m times d(sdot)/dv
    grad.segment<3>(3 * c.node) += m * c.n;
    for (const Term& t : c.terms)
      for (int j = 0; j < 3; ++j) grad.segment<3>(3 * t.tri[j]) -= m * t.omega * t.weights[j] * t.n;
  }
}

void SelfContact::add_damping_jacobian(const Points& x, double* neg_dfdv) const {
  if (law_.damping <= 0 || !neg_dfdv) return;
  for (const Pair& c : pairs(x)) {
    const double k = law_.per_area ? law_.stiffness * area_[c.node] : law_.stiffness, p = law_.thickness - c.d;
    auto add = [&](int node, const Vec3& g) {
      const int f = dofs_.free_index[node];
      if (f < 0) return;
      const Mat3 D = k * law_.damping * p * p * g * g.transpose();
      for (int e = 0; e < 9; ++e) neg_dfdv[diag_slots_[9 * f + e]] += D(e / 3, e % 3);
    };
    add(c.node, c.n);
    for (const Term& t : c.terms)
      for (int j = 0; j < 3; ++j) add(t.tri[j], t.omega * t.weights[j] * t.n);
  }
}

}  // namespace isochor
