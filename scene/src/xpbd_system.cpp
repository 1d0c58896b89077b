#include "isochor/scene/xpbd_system.hpp"
#include "isochor/scene/supports_setup.hpp"

#include <Eigen/Dense>
#include <map>
#include <algorithm>
#include <cmath>
#include <limits>

#include "isochor/models/assembly.hpp"
#include "isochor/base/error.hpp"
#include "isochor/models/supports.hpp"
#include "isochor/models/material.hpp"
#include "isochor/scene/mesh_system.hpp"

namespace isochor {

XpbdMeshSystem::XpbdMeshSystem(const Scene& scene) : scene_(scene), dofs_(scene_dofs(scene)) {
  if (scene.damping.alpha != 0 || scene.damping.beta != 0)
    throw Error(scene.file.name() +
                ": [damping] is not available with integrator.kind = \"xpbd\" (expected no Rayleigh damping)");
  if (!scene.loads.empty() || !scene.pressure_loads.empty())
    throw Error(scene.file.name() +
                ": [[load]] is not available with integrator.kind = \"xpbd\" (expected gravity as its only load)");
  // The same supports (and checks) as the other models, grouped by node for the projection.
  if (const auto supports = make_supports(scene, dofs_)) {
    std::map<int, std::size_t> held_at;
    for (const ComponentSupports::Row& r : supports->rows()) {
      auto [it, added] = held_at.try_emplace(r.node, held_.size());
      if (added) held_.push_back({r.node, {}, {}});
      held_[it->second].dirs.push_back(r.dir);
      held_[it->second].drivers.push_back(r.driver);
    }
  }
  if (scene.self_contact.enabled)
    throw Error(scene.file.name() +
                ": [contact.self] is not available with integrator.kind = \"xpbd\" (expected no contact "
                "between body parts)");
  for (const Collider& c : scene.colliders)
    if (c.law.damping != 0 || c.law.friction != 0)
      throw Error(scene.file.name() + ": " + c.name +
                  ": contact damping and friction are not available with integrator.kind = "
                  "\"xpbd\" (its contact is a projection onto the collider's surface; expected damping = 0 "
                  "and friction = 0)");
  const Mesh& mesh = scene.mesh;
  const double mu = scene.material.mu, lambda = scene.material.lambda;
  const double lambda_p = std::isinf(lambda) ? lambda : lambda + mu;
  gamma_ = std::isinf(lambda_p) ? 1.0 : 1.0 + mu / lambda_p;
  const Points& X = mesh.rest_positions();
  for (const Tet& t : mesh.tets()) {
    shapes_.push_back(TetShape::make(X.col(t[0]), X.col(t[1]), X.col(t[2]), X.col(t[3])));
    const double V = shapes_.back().rest_volume;
    alpha_d_.push_back(1.0 / (mu * V));
    alpha_h_.push_back(std::isinf(lambda_p) ? 0.0 : 1.0 / (lambda_p * V));
  }
  const Eigen::VectorXd m = lumped_mass(mesh, scene.material.density);
  w_.resize(mesh.num_nodes());
  w_.setZero();
  for (int n : dofs_.free_nodes) w_[n] = 1.0 / m[n];
  // Zone constraints over the free dofs (the pattern is only needed for Hessians, not used here).
  std::vector<std::vector<int>> elements;
  for (const Tet& t : mesh.tets()) elements.emplace_back(t.begin(), t.end());
  const Pattern pattern = pattern_from_elements(dofs_, elements);
  zones_ = VolumeConstraints::zones(mesh, scene.keep_zones ? scene_zone_tets(scene) : std::vector<std::vector<int>>{},
                                    dofs_, pattern);
  if (scene.zone_restore_time > 0)
    zones_.restore_from(scene.initial_positions.cols() ? scene.initial_positions : mesh.rest_positions(),
                        scene.frames.times().front(), scene.zone_restore_time);
  zone_grad_.resize(zones_.size());
  for (int j = 0; j < zones_.size(); ++j) zone_grad_[j].resize(zones_.row_dofs(j).size());
}

void XpbdMeshSystem::initial_state(double t0, Eigen::VectorXd& x, Eigen::VectorXd& v) {
  const Points& X = start                             ? start->positions
                    : scene_.initial_positions.cols() ? scene_.initial_positions
                                                      : scene_.mesh.rest_positions();
  x = Eigen::Map<const Eigen::VectorXd>(X.data(), X.size());
  v.resize(x.size());
  for (int n = 0; n < scene_.mesh.num_nodes(); ++n) v.segment<3>(3 * n) = scene_.start_velocity(start, n);
  prescribe(t0, x, v);
}

void XpbdMeshSystem::external_acceleration(double t, Eigen::VectorXd& a) {
  const double s = scene_.gravity_scale(t);
  a.resize(3 * num_points());
  for (int n = 0; n < num_points(); ++n) a.segment<3>(3 * n) = s * scene_.gravity;
}

void XpbdMeshSystem::prescribe(double t, Eigen::VectorXd& x, Eigen::VectorXd& v) {
  t_ = t;
  if (scene_.boundary.empty() && !scene_.skeleton) return;
  Points xp = Eigen::Map<const Points>(x.data(), 3, num_points());
  scene_.drive(t, xp, &v);
  x = Eigen::Map<const Eigen::VectorXd>(xp.data(), xp.size());
  hold(t, x, &v);
}

void XpbdMeshSystem::hold(double t, Eigen::VectorXd& x, Eigen::VectorXd* v) const {
  const Points& X = scene_.mesh.rest_positions();
  for (const Held& h : held_) {
    const int k = static_cast<int>(h.dirs.size());
    Eigen::MatrixXd D(3, k);
    Eigen::VectorXd r(k), rv(k);
    for (int j = 0; j < k; ++j) {
      D.col(j) = h.dirs[j];
      r[j] = h.dirs[j].dot(x.segment<3>(3 * h.node) - X.col(h.node) - h.drivers[j]->displacement(t));
      if (v) rv[j] = h.dirs[j].dot(v->segment<3>(3 * h.node) - h.drivers[j]->velocity(t));
    }
    // The nearest point (and velocity) that satisfies every held direction: D (D^T D)^-1 r off.
    const Eigen::MatrixXd DtD = D.transpose() * D;
    x.segment<3>(3 * h.node) -= D * DtD.ldlt().solve(r);
    if (v) v->segment<3>(3 * h.node) -= D * DtD.ldlt().solve(rv);
  }
}

double XpbdMeshSystem::constraint(int c, const Eigen::VectorXd& x, std::vector<int>& points,
                                  std::vector<double>& grad) {
  const int e = c / 2;
  const Tet& t = scene_.mesh.tets()[e];
  const TetShape& s = shapes_[e];
  Vec12 xe;
  for (int k = 0; k < 4; ++k) xe.segment<3>(3 * k) = x.segment<3>(3 * t[k]);
  const Mat3 F = s.F(xe);
  double value;
  Vec9 dC;
  if (c % 2 == 0) {  // deviatoric: sqrt(I_C), gradient F / sqrt(I_C)
    value = F.norm();
    dC = Eigen::Map<const Vec9>(F.data()) / value;
  } else {  // hydrostatic: det F - gamma, gradient cof F
    value = F.determinant() - gamma_;
    dC = cofactor_vec(F);
  }
  const Vec12 g = s.scatter(Eigen::Map<const Mat3>(dC.data()));
  points.assign(t.begin(), t.end());
  grad.assign(g.data(), g.data() + 12);
  return value;
}

void XpbdMeshSystem::after_sweep(double, Eigen::VectorXd& x) {
  project_zones(x);
  hold(t_, x, nullptr);  // last: the held components exactly, the zones to the sweeps' tolerance
}

void XpbdMeshSystem::project_zones(Eigen::VectorXd& x) {
  if (zones_.size() == 0) return;
  zones_.set_time(t_);
  // Each zone: one hard constraint V_j(x) = V_j(rest) (or its restore_time target), projected in turn with fresh
  // values.
  for (int j = 0; j < zones_.size(); ++j) {
    const Points xp = Eigen::Map<const Points>(x.data(), 3, num_points());
    zones_.value(xp, zone_value_);
    zones_.gradient(xp, zone_grad_);
    const auto& rows = zones_.row_dofs(j);
    double denom = 0;
    for (std::size_t k = 0; k < rows.size(); ++k)
      denom += w_[dofs_.free_nodes[rows[k] / 3]] * zone_grad_[j][k] * zone_grad_[j][k];
    if (denom <= 0) continue;
    const double dl = -zone_value_[j] / denom;
    for (std::size_t k = 0; k < rows.size(); ++k) {
      const int n = dofs_.free_nodes[rows[k] / 3];
      x[3 * n + rows[k] % 3] += w_[n] * zone_grad_[j][k] * dl;
    }
  }
}

void XpbdMeshSystem::project_collisions(double t, Eigen::VectorXd& x) {
  for (const Collider& c : scene_.colliders) {
    const ColliderPose P = c.pose(t, scene_.skeleton.get());
    for (int node : dofs_.free_nodes) {
      Eigen::Vector3d n;
      const double s = c.distance(P, x.segment<3>(3 * node), &n, nullptr);
      if (s < 0) x.segment<3>(3 * node) -= s * n;  // onto the surface (exactly for a plane, to first order else)
    }
  }
}

}  // namespace isochor
