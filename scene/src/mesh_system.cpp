#include "isochor/scene/mesh_system.hpp"
#include "isochor/scene/body_setup.hpp"
#include "isochor/scene/supports_setup.hpp"

#include <algorithm>
#include <cmath>

#include "isochor/base/error.hpp"
#include "isochor/models/supports.hpp"

namespace isochor {

std::shared_ptr<const Material> make_material(const MaterialSpec& m) {
  switch (m.model) {
    case MaterialModel::unh:
      return make_unh(m.mu, m.lambda);
    case MaterialModel::snh:
      return make_snh(m.mu, m.lambda);
    case MaterialModel::cnh:
      return make_cnh(m.mu, m.lambda, m.beta, m.epsilon);
    case MaterialModel::snh_simple:
      return make_xpbd_pair(m.mu, m.lambda);
    case MaterialModel::mass_spring:
      break;
  }
  throw Error("material.model = \"mass_spring\" is not a tet material (expected cnh, unh, snh or snh_simple)");
}

// The free nodes along a Morton curve through the rest positions, not in the mesh file's order (a
// mesher's numbering scatters neighbours over the whole range): the rows of the matrices a node
// touches, and the vector entries a product with them reads, lie close together, so a thread that
// owns a range of rows reads mostly its own range (docs/results/threads_ida.md).
DofMap scene_dofs(const Scene& s) { return scene_dofs(s, {}); }

// On P ranks, rank after rank, each rank's nodes along the curve: each rank's dofs are one range.
DofMap scene_dofs(const Scene& s, const std::vector<int>& node_rank) {
  std::vector<int> order = morton_order(s.mesh.rest_positions());
  if (!node_rank.empty())
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return node_rank[a] < node_rank[b]; });
  return DofMap::make(s.mesh.num_nodes(), s.driven_nodes(), order);
}

std::vector<int> scene_node_ranks(const Scene& s, int parts) {
  const int N = s.mesh.num_nodes();
  std::vector<std::vector<Index>> nbr(N);
  for (const Tet& t : s.mesh.tets())
    for (int a : t)
      for (int b : t)
        if (a != b) nbr[a].push_back(b);
  std::vector<Index> ptr{0}, adj;
  for (auto& list : nbr) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
    adj.insert(adj.end(), list.begin(), list.end());
    ptr.push_back(static_cast<Index>(adj.size()));
  }
  // The ranks' rows of CG balanced: driven nodes weigh nothing (the pinned cube's fixed face in
  // one part gave that part 7% fewer rows on 2 ranks).
  std::vector<int> weight(N, 1);
  for (int v : s.driven_nodes()) weight[v] = 0;
  return partition_graph(ptr, adj, parts, weight);
}

std::vector<std::vector<int>> scene_zone_tets(const Scene& s) {
  std::vector<std::vector<int>> z;
  for (const auto& [name, tets] : s.zones) z.push_back(tets);
  return z;
}

namespace {

// The zones' constraint rows: every zone but those whose volumes follow from the others'
// (Scene::redundant_zones), each with a free node on its boundary, moving to the rest volumes
// over zones.restore_time where that is set.
std::unique_ptr<VolumeConstraints> zone_constraints(const Scene& scene, const std::vector<std::vector<int>>& all_zones,
                                                    const DofMap& dofs, const Pattern& pattern) {
  std::vector<int> kept;
  std::vector<std::vector<int>> kept_tets;
  for (std::size_t j = 0; j < all_zones.size(); ++j)
    if (!std::binary_search(scene.redundant_zones.begin(), scene.redundant_zones.end(), static_cast<int>(j))) {
      kept.push_back(static_cast<int>(j));
      kept_tets.push_back(all_zones[j]);
    }
  auto zones = std::make_unique<VolumeConstraints>(VolumeConstraints::zones(scene.mesh, kept_tets, dofs, pattern));
  for (int j = 0; j < zones->size(); ++j)
    if (zones->row_dofs(j).empty())
      throw Error(scene.file.name() + ": zone \"" + scene.zones[static_cast<std::size_t>(kept[j])].first +
                  "\" has only driven nodes on its boundary: its volume cannot be kept");
  if (scene.zone_restore_time > 0)
    zones->restore_from(scene.initial_positions.cols() ? scene.initial_positions : scene.mesh.rest_positions(),
                        scene.frames.times().front(), scene.zone_restore_time);
  return zones;
}

}  // namespace

MeshSystem::MeshSystem(const Scene& scene, const Ranks* ranks)
    : scene_(scene),
      node_rank_(ranks && ranks->size() > 1 ? scene_node_ranks(scene, ranks->size()) : std::vector<int>()),
      dofs_(scene_dofs(scene, node_rank_)),
      material_(make_material(scene.material)) {
  if (dofs_.num_free() == 0)
    throw Error(scene.file.name() + ": every node is driven (by [[boundary]] or a bone): nothing to simulate");
  elastic_ = std::make_unique<ElasticAssembly>(
      scene.mesh, material_, dofs_, EpidermisSpec{scene.material.epidermis_lambda, scene.material.epidermis_gamma});
  if (!node_rank_.empty()) {
    elastic_->keep_rank(node_rank_, ranks->rank());
    partition_.ranks = ranks;
    partition_.offsets.assign(ranks->size() + 1, 0);
    for (int v : dofs_.free_nodes) partition_.offsets[node_rank_[v] + 1] += 3;
    for (int r = 0; r < ranks->size(); ++r) partition_.offsets[r + 1] += partition_.offsets[r];
    value_offsets_ = partition_.value_offsets(elastic_->pattern());
  }
  if (!scene.muscles.empty()) elastic_->set_fibres(scene_fibre_field(scene));
  const TetMaterials regions = scene_tet_materials(scene);
  elastic_->set_tet_materials(regions.materials, regions.material_of);
  node_mass_ = lumped_mass(scene.mesh, scene.material.density, regions.density.empty() ? nullptr : &regions.density);
  const Eigen::VectorXd area = surface_areas(scene.mesh);
  external_ = std::make_unique<ExternalPotential>(node_mass_, scene.gravity, scene.colliders, dofs_,
                                                  elastic_->pattern(), area, scene.skeleton);
  external_->set_loads(scene.loads);
  if (scene.self_contact.enabled)
    external_->set_self_contact(std::make_unique<SelfContact>(scene.mesh, scene.self_contact.law,
                                                              scene.self_contact.exclude, dofs_, elastic_->pattern(),
                                                              area, scene.self_contact.smoothing));
  pressure_loads_ = std::make_unique<PressureLoads>(scene.pressure_loads, dofs_, elastic_->pattern());
  damping_ = scene.damping;
  const auto all_zones = scene_zone_tets(scene);
  zone_volumes_ = VolumeConstraints::zones(scene.mesh, all_zones, dofs_, elastic_->pattern());
  if (scene.keep_zones && !all_zones.empty())
    add_constraints(zone_constraints(scene, all_zones, dofs_, elastic_->pattern()));
  if (auto supports = make_supports(scene, dofs_)) add_constraints(std::move(supports));  // [[boundary]] components
  dof_mass_.resize(num_dofs());
  for (int f = 0; f < dofs_.num_free(); ++f) dof_mass_.segment<3>(3 * f).setConstant(node_mass_[dofs_.free_nodes[f]]);
  const double V = scene.mesh.rest_volume();
  force_scale_ = std::max(node_mass_.sum() * std::max(scene.gravity.norm(), 1.0), scene.material.mu * std::cbrt(V * V));
  x_ = scene.mesh.rest_positions();
  xdot_ = Eigen::VectorXd::Zero(3 * scene.mesh.num_nodes());
}

void MeshSystem::add_constraints(std::unique_ptr<ConstraintSet> set) {
  for (int j = 0; j < set->size(); ++j) {
    rows_.push_back(set->row_dofs(j));
    row_scale_.push_back(set->scale(j));
  }
  offset_.push_back(offset_.back() + set->size());
  sets_.push_back(std::move(set));
}

void MeshSystem::set_state(double t, const VectorXd& q, const VectorXd& v) {
  for (int f = 0; f < dofs_.num_free(); ++f) xdot_.segment<3>(3 * dofs_.free_nodes[f]) = v.segment<3>(3 * f);
  set_positions(t, q);
}

void scene_initial_state(const Scene& s, const DofMap& dofs, const StartState* start, VectorXd& q, VectorXd& v) {
  q.resize(3 * dofs.num_free());
  v.resize(3 * dofs.num_free());
  for (int f = 0; f < dofs.num_free(); ++f) {
    const int node = dofs.free_nodes[f];
    const Points& X = s.initial_positions.cols() ? s.initial_positions : s.mesh.rest_positions();
    q.segment<3>(3 * f) = start ? start->positions.col(node) : X.col(node);
    v.segment<3>(3 * f) = s.start_velocity(start, node);
  }
}

void scene_at_time(const Scene& s, double t, Points& x, Eigen::VectorXd& xdot, ExternalPotential& external) {
  s.drive(t, x, &xdot);
  external.set_time(t);
  external.set_gravity_scale(s.gravity_scale(t));
}

void MeshSystem::initial_state(double t0, VectorXd& q, VectorXd& v) {
  scene_initial_state(scene_, dofs_, start(), q, v);
  state_t_ = std::numeric_limits<double>::quiet_NaN();
  set_state(t0, q, v);
}

void MeshSystem::force(double t, const VectorXd& q, const VectorXd& v, VectorXd& f) {
  // One pass over the elements for the elastic force and the Rayleigh term beta K v (each
  // element's F and material evaluated once).
  force_and_jacobians(t, q, v, f, nullptr, nullptr);
}

void MeshSystem::add_force_jacobians(double t, const VectorXd& q, const VectorXd& v, double* neg_dfdq,
                                     double* neg_dfdv) {
  set_state(t, q, v);
  // -df/dv = alpha M + beta K: the element Hessians of K are computed once for both outputs.
  const RayleighDamping damping = damping_on_ ? damping_ : RayleighDamping{};
  double* damped = neg_dfdv && damping.beta != 0 ? neg_dfdv : nullptr;
  if (neg_dfdq) {
    elastic_->add_hessian(x_, 1.0, neg_dfdq, damping.beta, damped, project_hessian_);
    external_->add_hessian(x_, 1.0, neg_dfdq);
    pressure_loads_->add_jacobian(x_, neg_dfdq);
  } else if (damped) {
    elastic_->add_hessian(x_, damping.beta, damped, 0.0, nullptr, project_hessian_);
  }
  if (damping_on_) external_->add_damping_jacobians(x_, xdot_, neg_dfdq, neg_dfdv);
  if (neg_dfdv && damping.alpha != 0)
    RayleighDamping{damping.alpha, 0.0}.add_matrix(*elastic_, node_mass_, x_, 1.0, neg_dfdv);
  share(nullptr, neg_dfdq, neg_dfdv);
}

void MeshSystem::force_and_jacobians(double t, const VectorXd& q, const VectorXd& v, VectorXd& f, double* neg_dfdq,
                                     double* neg_dfdv) {
  set_state(t, q, v);
  // One pass over the elements: gradient, K into -df/dq, beta K into -df/dv, and beta K v.
  ElementPass p;
  grad_.setZero(3 * x_.cols());
  p.grad = &grad_;
  p.values = neg_dfdq;
  p.project = project_hessian_;
  const RayleighDamping damping = damping_on_ ? damping_ : RayleighDamping{};
  if (neg_dfdv && damping.beta != 0) {
    p.values2 = neg_dfdv;
    p.scale2 = damping.beta;
  }
  if (damping.beta != 0) {
    kv_.setZero(3 * x_.cols());
    p.v = &xdot_;
    p.v_scale = damping.beta;
    p.Kv = &kv_;
  }
  elastic_->evaluate(x_, p);
  external_->add_gradient(x_, grad_);
  if (neg_dfdq) external_->add_hessian(x_, 1.0, neg_dfdq);
  if (damping_on_) {
    external_->add_damping(x_, xdot_, grad_);
    external_->add_damping_jacobians(x_, xdot_, neg_dfdq, neg_dfdv);
  }
  pressure_loads_->add_gradient(x_, grad_);
  if (neg_dfdq) pressure_loads_->add_jacobian(x_, neg_dfdq);
  if (damping.beta != 0) grad_ += kv_;
  f.resize(num_dofs());
  for (int k = 0; k < dofs_.num_free(); ++k) {
    const int n = dofs_.free_nodes[k];
    f.segment<3>(3 * k) = -grad_.segment<3>(3 * n) - damping.alpha * node_mass_[n] * xdot_.segment<3>(3 * n);
  }
  if (neg_dfdv && damping.alpha != 0)
    RayleighDamping{damping.alpha, 0.0}.add_matrix(*elastic_, node_mass_, x_, 1.0, neg_dfdv);
  share(&f, neg_dfdq, neg_dfdv);
}

void MeshSystem::share(VectorXd* f, double* neg_dfdq, double* neg_dfdv) const {
  if (!partition_.ranks) return;
  if (f) partition_.ranks->share(f->data(), partition_.offsets);
  if (neg_dfdq) partition_.ranks->share(neg_dfdq, value_offsets_);
  if (neg_dfdv) partition_.ranks->share(neg_dfdv, value_offsets_);
}

double MeshSystem::elastic_energy() const {
  double E = elastic_->energy(x_);
  if (partition_.ranks) partition_.ranks->sum(&E, 1);
  return E;
}

void MeshSystem::loads(Points& out) const {
  Eigen::VectorXd g = Eigen::VectorXd::Zero(x_.size());
  external_->add_load_gradient(g);
  pressure_loads_->add_gradient(x_, g);
  out = -Eigen::Map<const Points>(g.data(), 3, x_.cols());
}

void MeshSystem::set_positions(double t, const VectorXd& q) {
  for (int f = 0; f < dofs_.num_free(); ++f) x_.col(dofs_.free_nodes[f]) = q.segment<3>(3 * f);
  if (t != state_t_) {
    scene_at_time(scene_, t, x_, xdot_, *external_);
    pressure_loads_->set_time(t);
    for (auto& set : sets_) set->set_time(t);
    if (elastic_->has_fibres()) elastic_->set_activations(activation_fn_ ? activation_fn_(t) : scene_.activations(t));
    state_t_ = t;
  }
}

void MeshSystem::constraint(double t, const VectorXd& q, VectorXd& g) {
  set_positions(t, q);
  g.resize(num_constraints());
  for (std::size_t s = 0; s < sets_.size(); ++s) sets_[s]->value(x_, g.data() + offset_[s]);
}

void MeshSystem::constraint_jacobian(double t, const VectorXd& q, std::vector<std::vector<double>>& G, VectorXd* g_t) {
  set_positions(t, q);  // dg/dt needs only the driven nodes' velocities
  G.resize(num_constraints());
  if (g_t) g_t->resize(num_constraints());
  for (std::size_t s = 0; s < sets_.size(); ++s) {
    sets_[s]->gradient(x_, G.data() + offset_[s]);
    if (g_t) sets_[s]->time_derivative(x_, xdot_, g_t->data() + offset_[s]);
  }
}

void MeshSystem::add_constraint_hessian(double t, const VectorXd& q, const VectorXd& w, double scale, double* values) {
  set_positions(t, q);
  for (std::size_t s = 0; s < sets_.size(); ++s) sets_[s]->add_hessian(x_, w.data() + offset_[s], scale, values);
}

void MeshSystem::constraint_velocity_jacobian(double t, const VectorXd& q, const VectorXd& v,
                                              std::vector<std::vector<double>>& rows) {
  set_state(t, q, v);
  rows.resize(num_constraints());
  for (std::size_t s = 0; s < sets_.size(); ++s) sets_[s]->hessian_times(x_, xdot_, rows.data() + offset_[s]);
}

bool MeshSystem::potential(double t, const VectorXd& q, double& V) {
  if (!pressure_loads_->empty()) return false;  // follower loads have no potential
  set_positions(t, q);
  V = elastic_energy() + external_->energy(x_);
  return true;
}

std::array<double, 3> MeshSystem::energies() const {
  double kinetic = 0;
  for (int n = 0; n < x_.cols(); ++n) kinetic += 0.5 * node_mass_[n] * xdot_.segment<3>(3 * n).squaredNorm();
  return {kinetic, elastic_energy(), external_->energy(x_)};
}

std::vector<double> MeshSystem::volumes() const {
  std::vector<double> v{tets_volume(x_, scene_.mesh.tets())};
  Eigen::VectorXd z;
  zone_volumes_.volumes(x_, z);
  v.insert(v.end(), z.data(), z.data() + z.size());
  return v;
}

void MeshSystem::pressures(const VectorXd& lambda, std::vector<double>& p) const {
  elastic_->pressures(x_, p);
  if (lambda.size())
    for (std::size_t s = 0; s < sets_.size(); ++s) sets_[s]->add_pressure(lambda.data() + offset_[s], p);
}

}  // namespace isochor

namespace isochor {

bool MeshSystem::rescale_volume(double t, VectorXd& q) {
  // x_i(s) = c + s (x_i - c) for the free nodes (driven ones stay), c the centre of mass; the
  // total volume is a cubic in s: Newton from s = 1 with dV/ds = sum_i grad_i V . (x_i - c).
  set_positions(t, q);
  const Mesh& mesh = scene_.mesh;
  const double V0 = mesh.rest_volume();
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int n = 0; n < x_.cols(); ++n) c += node_mass_[n] * x_.col(n);
  c /= node_mass_.sum();
  const Points base = x_;
  double s = 1.0;
  for (int it = 0; it < 30; ++it) {
    for (int n : dofs_.free_nodes) x_.col(n) = c + s * (base.col(n) - c);
    double V = 0, dV = 0;
    for (const Tet& t : mesh.tets()) {
      Vec12 xe, g;
      for (int k = 0; k < 4; ++k) xe.segment<3>(3 * k) = x_.col(t[k]);
      V += tet_volume(xe, &g, nullptr);
      for (int k = 0; k < 4; ++k)
        if (dofs_.free_index[t[k]] >= 0) dV += g.segment<3>(3 * k).dot(base.col(t[k]) - c);
    }
    if (std::abs(V - V0) <= 1e-14 * V0 || dV == 0) break;
    s -= (V - V0) / dV;
  }
  for (int f = 0; f < dofs_.num_free(); ++f) q.segment<3>(3 * f) = x_.col(dofs_.free_nodes[f]);
  return true;
}

}  // namespace isochor
