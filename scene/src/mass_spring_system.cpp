#include "isochor/scene/mass_spring_system.hpp"
#include "isochor/scene/supports_setup.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "isochor/base/error.hpp"
#include "isochor/scene/mesh_system.hpp"

namespace isochor {

namespace {
Vec6 gather2(const Points& x, int a, int b) {
  Vec6 v;
  v << x.col(a), x.col(b);
  return v;
}
Vec6 gather2v(const Eigen::VectorXd& v, int a, int b) {
  Vec6 r;
  r << v.segment<3>(3 * a), v.segment<3>(3 * b);
  return r;
}
}  // namespace

MassSpringSystem::MassSpringSystem(const Scene& scene) : scene_(scene) {
  const Mesh& mesh = scene.mesh;
  const int N = mesh.num_nodes();
  if (!scene.zones.empty())
    throw Error(scene.file.name() +
                ": [zones] are not available with material.model = \"mass_spring\" (it keeps the "
                "volume enclosed by its surface; expected no zones)");
  if (!scene.pressure_loads.empty())
    throw Error(scene.file.name() +
                ": a pressure [[load]] is not available with material.model = \"mass_spring\" (expected "
                "point loads or tractions)");
  std::vector<char> moving(N, 0);
  for (int v : mesh.surface_nodes()) moving[v] = 1;
  // Driven surface nodes follow their drivers; driven interior nodes are carried like the rest
  // of the interior (the model has no interior).
  for (int v : scene.driven_nodes()) moving[v] = 0;
  std::vector<int> fixed;
  for (int v = 0; v < N; ++v)
    if (!moving[v]) fixed.push_back(v);
  dofs_ = DofMap::make(N, fixed);
  if (dofs_.num_free() == 0) throw Error(scene.file.name() + ": every surface node is driven: nothing to simulate");
  const Points& X = mesh.rest_positions();
  springs_ = surface_springs(X, mesh.surface());
  k_ = scene.material.spring_stiffness;
  c_ = scene.material.spring_damping;
  constrained_ = scene.material.volume_constraint;
  std::vector<std::vector<int>> elements;
  for (const Spring& s : springs_) elements.push_back({s.a, s.b});
  for (const Tri& t : mesh.surface()) elements.push_back({t[0], t[1], t[2]});
  pattern_ = pattern_from_elements(dofs_, elements);
  for (const Spring& s : springs_) {
    const int nodes[2] = {s.a, s.b};
    const auto slots = slot_map(pattern_, dofs_, nodes, 2);
    spring_slots_.insert(spring_slots_.end(), slots.begin(), slots.end());
  }
  // Mass: the body's mass shared by surface area (a third of each triangle's area per corner).
  node_mass_ = Eigen::VectorXd::Zero(N);
  double area = 0;
  for (const Tri& t : mesh.surface()) {
    const double a = 0.5 * (X.col(t[1]) - X.col(t[0])).cross(X.col(t[2]) - X.col(t[0])).norm();
    for (int v : t) node_mass_[v] += a / 3;
    area += a;
  }
  node_mass_ *= scene.material.density * mesh.rest_volume() / area;
  dof_mass_.resize(num_dofs());
  for (int f = 0; f < dofs_.num_free(); ++f) dof_mass_.segment<3>(3 * f).setConstant(node_mass_[dofs_.free_nodes[f]]);
  if (scene.self_contact.enabled)
    throw Error(scene.file.name() +
                ": [contact.self] is not available with the mass-spring model (expected no contact "
                "between body parts)");
  external_ = std::make_unique<ExternalPotential>(node_mass_, scene.gravity, scene.colliders, dofs_, pattern_,
                                                  surface_areas(scene.mesh), scene.skeleton);
  external_->set_loads(scene.loads);
  volume_ = VolumeConstraints::surface(mesh, dofs_, pattern_);
  rest_volume_ = volume_.rest_volumes()[0];
  if (constrained_) rows_.push_back(volume_.row_dofs(0));
  supports_ = make_supports(scene, dofs_);
  if (supports_)
    for (int j = 0; j < supports_->size(); ++j) rows_.push_back(supports_->row_dofs(j));
  double Lmean = 0;
  for (const Spring& s : springs_) Lmean += s.rest_length / springs_.size();
  force_scale_ = std::max(node_mass_.sum() * std::max(scene.gravity.norm(), 1.0), k_ * Lmean);
  // Interior nodes are carried by their 8 nearest surface nodes (inverse-distance weights).
  carry_.resize(N);
  const auto& surf = mesh.surface_nodes();
  for (int v = 0; v < N; ++v) {
    if (std::binary_search(surf.begin(), surf.end(), v)) continue;
    std::vector<std::pair<double, int>> d;
    for (int s : surf) d.emplace_back((X.col(s) - X.col(v)).norm(), s);
    const std::size_t k = std::min<std::size_t>(8, d.size());
    std::partial_sort(d.begin(), d.begin() + k, d.end());
    double sum = 0;
    for (std::size_t i = 0; i < k; ++i) sum += 1 / d[i].first;
    for (std::size_t i = 0; i < k; ++i) carry_[v].emplace_back(d[i].second, 1 / d[i].first / sum);
  }
  x_ = X;
  xdot_ = Eigen::VectorXd::Zero(3 * N);
}

void MassSpringSystem::initial_state(double t0, VectorXd& q, VectorXd& v) {
  scene_initial_state(scene_, dofs_, start(), q, v);
  state_t_ = std::numeric_limits<double>::quiet_NaN();
  set_state(t0, q, v);
}

void MassSpringSystem::place(double t, const VectorXd& q) {
  for (int f = 0; f < dofs_.num_free(); ++f) x_.col(dofs_.free_nodes[f]) = q.segment<3>(3 * f);
  if (t != state_t_) {
    scene_at_time(scene_, t, x_, xdot_, *external_);
    if (supports_) supports_->set_time(t);
    state_t_ = t;
  }
}

void MassSpringSystem::place(double t, const VectorXd& q, const VectorXd& v) {
  for (int f = 0; f < dofs_.num_free(); ++f) xdot_.segment<3>(3 * dofs_.free_nodes[f]) = v.segment<3>(3 * f);
  place(t, q);
}

void MassSpringSystem::set_state(double t, const VectorXd& q, const VectorXd& v) {
  place(t, q, v);
  // Interior nodes are only carried for output; forces and the constraint never read them.
  const Points& X = scene_.mesh.rest_positions();
  for (std::size_t n = 0; n < carry_.size(); ++n) {
    if (carry_[n].empty()) continue;
    Eigen::Vector3d u = Eigen::Vector3d::Zero(), w = Eigen::Vector3d::Zero();
    for (const auto& [s, weight] : carry_[n]) {
      u += weight * (x_.col(s) - X.col(s));
      w += weight * xdot_.segment<3>(3 * s);
    }
    x_.col(n) = X.col(n) + u;
    xdot_.segment<3>(3 * n) = w;
  }
}

void MassSpringSystem::force(double t, const VectorXd& q, const VectorXd& v, VectorXd& f) {
  place(t, q, v);
  Eigen::VectorXd& grad = grad_;  // a member: no allocation in a residual after the first
  grad.setZero(3 * x_.cols());
  external_->add_gradient(x_, grad);
  external_->add_damping(x_, xdot_, grad);
  for (const Spring& s : springs_) {
    Vec6 g;
    spring_energy(k_, s.rest_length, gather2(x_, s.a, s.b), &g, nullptr);
    if (c_ != 0) g -= spring_damping_force(c_, gather2(x_, s.a, s.b), gather2v(xdot_, s.a, s.b), nullptr, nullptr);
    grad.segment<3>(3 * s.a) += g.head<3>();
    grad.segment<3>(3 * s.b) += g.tail<3>();
  }
  f.resize(num_dofs());
  for (int k = 0; k < dofs_.num_free(); ++k) f.segment<3>(3 * k) = -grad.segment<3>(3 * dofs_.free_nodes[k]);
}

void MassSpringSystem::add_force_jacobians(double t, const VectorXd& q, const VectorXd& v, double* neg_dfdq,
                                           double* neg_dfdv) {
  place(t, q, v);
  if (neg_dfdq) external_->add_hessian(x_, 1.0, neg_dfdq);
  external_->add_damping_jacobians(x_, xdot_, neg_dfdq, neg_dfdv);
  for (std::size_t i = 0; i < springs_.size(); ++i) {
    const Spring& s = springs_[i];
    Mat6 K = Mat6::Zero(), Dx = Mat6::Zero(), Dv = Mat6::Zero();
    spring_energy(k_, s.rest_length, gather2(x_, s.a, s.b), nullptr, &K);
    if (c_ != 0) spring_damping_force(c_, gather2(x_, s.a, s.b), gather2v(xdot_, s.a, s.b), &Dx, &Dv);
    const Index* slots = spring_slots_.data() + 36 * i;
    for (int a = 0; a < 6; ++a)
      for (int b = 0; b < 6; ++b) {
        const Index sl = slots[6 * a + b];
        if (sl < 0) continue;
        if (neg_dfdq) neg_dfdq[sl] += K(a, b) - Dx(a, b);
        if (neg_dfdv) neg_dfdv[sl] -= Dv(a, b);
      }
  }
}

void MassSpringSystem::constraint(double t, const VectorXd& q, VectorXd& g) {
  place(t, q);
  g.resize(num_constraints());
  if (constrained_) volume_.value(x_, g.data());
  if (supports_) supports_->value(x_, g.data() + volume_rows());
}

void MassSpringSystem::constraint_jacobian(double t, const VectorXd& q, std::vector<std::vector<double>>& G,
                                           VectorXd* g_t) {
  place(t, q);
  G.resize(num_constraints());
  if (g_t) g_t->resize(num_constraints());
  if (constrained_) {
    volume_.gradient(x_, G.data());
    if (g_t) volume_.time_derivative(x_, xdot_, g_t->data());
  }
  if (supports_) {
    supports_->gradient(x_, G.data() + volume_rows());
    if (g_t) supports_->time_derivative(x_, xdot_, g_t->data() + volume_rows());
  }
}

void MassSpringSystem::add_constraint_hessian(double t, const VectorXd& q, const VectorXd& w, double scale,
                                              double* values) {
  place(t, q);
  if (constrained_) volume_.add_hessian(x_, w.data(), scale, values);  // the supports' rows are linear
}

void MassSpringSystem::constraint_velocity_jacobian(double t, const VectorXd& q, const VectorXd& v,
                                                    std::vector<std::vector<double>>& rows) {
  place(t, q, v);
  rows.resize(num_constraints());
  if (constrained_) volume_.hessian_times(x_, xdot_, rows.data());
  if (supports_) supports_->hessian_times(x_, xdot_, rows.data() + volume_rows());
}

std::array<double, 3> MassSpringSystem::energies() const {
  double kinetic = 0, springs = 0;
  for (int n : dofs_.free_nodes) kinetic += 0.5 * node_mass_[n] * xdot_.segment<3>(3 * n).squaredNorm();
  for (const Spring& s : springs_) springs += spring_energy(k_, s.rest_length, gather2(x_, s.a, s.b), nullptr, nullptr);
  return {kinetic, springs, external_->energy(x_)};
}

std::vector<double> MassSpringSystem::volumes() const {
  Eigen::VectorXd v;
  volume_.volumes(x_, v);
  return {v[0]};
}

Eigen::VectorXd MassSpringSystem::weights(const Eigen::Vector3d& center, double radius) const {
  // Hong et al.'s eq. (15), W = (cos(pi d / r) + 1) / 2 inside the zone d < r and 0 outside (the
  // converted text lost the pi; with it W falls smoothly to 0 at the zone's edge), normalised so
  // that the weights of the n free surface nodes sum to n.
  const int n = dofs_.num_free();
  Eigen::VectorXd w(n);
  for (int f = 0; f < n; ++f) {
    const double d = (x_.col(dofs_.free_nodes[f]) - center).norm();
    w[f] = d < radius ? 0.5 * (std::cos(M_PI * d / radius) + 1) : 0.0;
  }
  if (w.sum() <= 0) throw Error(scene_.file.name() + ": no surface node lies within the weight radius of its centre");
  return w * (n / w.sum());
}

std::unique_ptr<SceneSystem> make_scene_system(const Scene& scene, const Ranks* ranks) {
  if (scene.material.model == MaterialModel::mass_spring) return std::make_unique<MassSpringSystem>(scene);
  return std::make_unique<MeshSystem>(scene, ranks);
}

}  // namespace isochor
