#include "isochor/models/forces.hpp"
#include "isochor/models/material.hpp"
#include "isochor/base/error.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <map>
#include <set>
#include <stdexcept>

namespace isochor {

ExternalPotential::ExternalPotential(Eigen::VectorXd mass, Vec3 gravity, std::vector<Collider> colliders,
                                     const DofMap& dofs, const Pattern& pattern, Eigen::VectorXd area,
                                     std::shared_ptr<const Skeleton> skeleton)
    : mass_(std::move(mass)),
      gravity_(gravity),
      colliders_(std::move(colliders)),
      skeleton_(std::move(skeleton)),
      dofs_(dofs),
      area_(std::move(area)) {
  for (const Collider& c : colliders_) {
    if (c.law.per_area && area_.size() != mass_.size())
      throw Error("ExternalPotential: a per-area contact law needs every node's surface area");
    if (c.bone >= 0 && !skeleton_) throw Error("ExternalPotential: a collider on a bone needs the skeleton");
    damped_ = damped_ || c.law.damping > 0 || c.law.friction > 0;
    friction_ = friction_ || c.law.friction > 0;
  }
  poses_.resize(colliders_.size());
  set_time(0.0);
  diag_slots_.resize(9 * static_cast<std::size_t>(dofs.num_free()));
  for (int f = 0; f < dofs.num_free(); ++f)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) diag_slots_[9 * f + 3 * a + b] = pattern.find(3 * Index(f) + a, 3 * Index(f) + b);
}

void ExternalPotential::set_time(double t) {
  time_ = t;
  for (std::size_t k = 0; k < colliders_.size(); ++k) poses_[k] = colliders_[k].pose(t, skeleton_.get());
}

void ExternalPotential::pose_numbers(std::vector<double>& out) const {
  out.clear();
  for (const ColliderPose& P : poses_) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) out.push_back(P.A(r, c));
    out.insert(out.end(), P.b.data(), P.b.data() + 3);
  }
}

void ExternalPotential::scale_numbers(std::vector<double>& out) const {
  out.clear();
  for (const ColliderPose& P : poses_) out.push_back(P.radius_scale);
}

template <class F>
void ExternalPotential::for_each_contact(std::size_t c, const Points& x, bool free_only, F&& f) const {
  const Collider& C = colliders_[c];
  const ColliderPose& P = poses_[c];
  const double reach = C.shape.bound() * std::max(1.0, P.radius_scale) + C.law.thickness;
  const int count = free_only ? dofs_.num_free() : static_cast<int>(x.cols());
  for (int j = 0; j < count; ++j) {
    const int i = free_only ? dofs_.free_nodes[j] : j;
    // |l| - bound is a lower bound of s: nodes farther than bound + delta cannot touch.
    if ((x.col(i) - P.b).squaredNorm() > reach * reach) continue;
    // A mesh's distance alone costs a fifth of it with derivatives: most nodes are out of reach.
    if (C.shape.kind == ColliderShape::Kind::mesh && C.distance(P, x.col(i), nullptr, nullptr) >= C.law.thickness)
      continue;
    Vec3 n;
    Mat3 H;
    const double s = C.distance(P, x.col(i), &n, &H);
    if (s < C.law.thickness) f(j, i, stiffness(c, i), s, n, H);
  }
}

void ExternalPotential::add_damping(const Points& x, const Eigen::VectorXd& xdot, Eigen::VectorXd& grad) const {
  if (!damped_) return;
  if (self_) self_->add_damping(x, xdot, grad);
  for (std::size_t c = 0; c < colliders_.size(); ++c) {
    const ContactLaw& L = colliders_[c].law;
    if (L.damping <= 0 && L.friction <= 0) continue;
    const ColliderPose& P = poses_[c];
    for_each_contact(c, x, false, [&](int, int i, double k, double s, const Vec3& n, const Mat3& H) {
      const Vec3 vrel = xdot.segment<3>(3 * i) - P.velocity_at(x.col(i));
      grad.segment<3>(3 * i) -= contact_damping_force(k, L.damping, L.friction, L.slip_speed, L.thickness, s, n, H,
                                                      vrel, -skew(P.omega), nullptr, nullptr);
    });
  }
}

void ExternalPotential::add_damping_jacobians(const Points& x, const Eigen::VectorXd& xdot, double* neg_dfdx,
                                              double* neg_dfdv) const {
  if (!damped_ || (!neg_dfdx && !neg_dfdv)) return;
  if (self_) self_->add_damping_jacobian(x, neg_dfdv);
  for (std::size_t c = 0; c < colliders_.size(); ++c) {
    const ContactLaw& L = colliders_[c].law;
    if (L.damping <= 0 && L.friction <= 0) continue;
    const ColliderPose& P = poses_[c];
    for_each_contact(c, x, true, [&](int f, int i, double k, double s, const Vec3& n, const Mat3& H) {
      Mat3 Dx, Dv;
      const Vec3 vrel = xdot.segment<3>(3 * i) - P.velocity_at(x.col(i));
      contact_damping_force(k, L.damping, L.friction, L.slip_speed, L.thickness, s, n, H, vrel, -skew(P.omega), &Dx,
                            &Dv);
      for (int e = 0; e < 9; ++e) {
        if (neg_dfdx) neg_dfdx[diag_slots_[9 * f + e]] += Dx(e / 3, e % 3);
        if (neg_dfdv) neg_dfdv[diag_slots_[9 * f + e]] += Dv(e / 3, e % 3);
      }
    });
  }
}

void ExternalPotential::contact_forces(const Points& x, const Eigen::VectorXd* xdot, Points& out) const {
  out.setZero(3, x.cols());
  for (std::size_t c = 0; c < colliders_.size(); ++c) {
    const ContactLaw& L = colliders_[c].law;
    const ColliderPose& P = poses_[c];
    for_each_contact(c, x, false, [&](int, int i, double k, double s, const Vec3& n, const Mat3& H) {
      Vec3 g;
      contact_energy(k, L.thickness, s, n, H, &g, nullptr);
      out.col(i) -= g;
      if (xdot && (L.damping > 0 || L.friction > 0))
        out.col(i) +=
            contact_damping_force(k, L.damping, L.friction, L.slip_speed, L.thickness, s, n, H,
                                  xdot->segment<3>(3 * i) - P.velocity_at(x.col(i)), -skew(P.omega), nullptr, nullptr);
    });
  }
  if (self_) self_->add_forces(x, xdot, out);
}

double ExternalPotential::energy(const Points& x) const {
  Eigen::VectorXd unused = Eigen::VectorXd::Zero(3 * x.cols());
  return add_gradient(x, unused);
}

double ExternalPotential::add_load_gradient(Eigen::VectorXd& grad, const Points* x) const {
  double E = 0.0;
  for (const NodeLoad& l : loads_) {
    const double s = l.history.factor(time_);
    for (std::size_t k = 0; k < l.nodes.size(); ++k) {
      if (x) E -= s * l.force[k].dot(x->col(l.nodes[k]));
      grad.segment<3>(3 * l.nodes[k]) -= s * l.force[k];
    }
  }
  return E;
}

double ExternalPotential::add_gradient(const Points& x, Eigen::VectorXd& grad) const {
  double E = 0.0;
  const Vec3 gravity = g();
  E += add_load_gradient(grad, &x);
  for (int i = 0; i < x.cols(); ++i) {
    E -= mass_[i] * gravity.dot(x.col(i));
    grad.segment<3>(3 * i) -= mass_[i] * gravity;
  }
  for (std::size_t c = 0; c < colliders_.size(); ++c)
    for_each_contact(c, x, false, [&](int, int i, double k, double s, const Vec3& n, const Mat3& H) {
      Vec3 gk;
      E += contact_energy(k, colliders_[c].law.thickness, s, n, H, &gk, nullptr);
      grad.segment<3>(3 * i) += gk;
    });
  if (self_) E += self_->add_gradient(x, grad);
  return E;
}

void ExternalPotential::add_hessian(const Points& x, double scale, double* values) const {
  for (std::size_t c = 0; c < colliders_.size(); ++c)
    for_each_contact(c, x, true, [&](int f, int, double k, double s, const Vec3& n, const Mat3& H) {
      Mat3 He;
      contact_energy(k, colliders_[c].law.thickness, s, n, H, nullptr, &He);
      for (int e = 0; e < 9; ++e) values[diag_slots_[9 * f + e]] += scale * He(e / 3, e % 3);
    });
  if (self_) self_->add_hessian(x, scale, values);
}

double LoadHistory::factor(double t) const {
  if (!times.empty()) {
    if (t <= times.front()) return factors.front();
    if (t >= times.back()) return factors.back();
    const std::size_t i = static_cast<std::size_t>(std::upper_bound(times.begin(), times.end(), t) - times.begin()) - 1;
    const double s = (t - times[i]) / (times[i + 1] - times[i]);
    return (1 - s) * factors[i] + s * factors[i + 1];
  }
  return ramp > 0 ? std::clamp(t / ramp, 0.0, 1.0) : 1.0;
}

void LoadHistory::breakpoints(std::vector<double>& out) const {
  if (ramp > 0) out.push_back(ramp);
  out.insert(out.end(), times.begin(), times.end());
}

PressureLoads::PressureLoads(std::vector<PressureLoad> loads, const DofMap& dofs, const Pattern& pattern)
    : loads_(std::move(loads)) {
  for (const PressureLoad& l : loads_) {
    std::vector<Index> s;
    for (const Tri& t : l.faces) {
      const auto m = slot_map(pattern, dofs, t.data(), 3);
      s.insert(s.end(), m.begin(), m.end());
    }
    slots_.push_back(std::move(s));
  }
}

void PressureLoads::add_gradient(const Points& x, Eigen::VectorXd& grad) const {
  for (const PressureLoad& l : loads_) {
    const double p = l.pressure * l.history.factor(time_);
    for (const Tri& t : l.faces) {
      const Vec3 a = 0.5 * (x.col(t[1]) - x.col(t[0])).cross(x.col(t[2]) - x.col(t[0]));
      for (int v : t) grad.segment<3>(3 * v) += p / 3.0 * a;
    }
  }
}

void PressureLoads::add_jacobian(const Points& x, double* values) const {
  for (std::size_t k = 0; k < loads_.size(); ++k) {
    const PressureLoad& l = loads_[k];
    const double p = l.pressure * l.history.factor(time_);
    for (std::size_t f = 0; f < l.faces.size(); ++f) {
      const Tri& t = l.faces[f];
      const Index* s = slots_[k].data() + 81 * f;
      for (int j = 0; j < 3; ++j) {
        // d a / d x_j = skew(x_(j+2) - x_(j+1)) / 2; -df_i/dx_j = p / 3 d a / d x_j for every corner i.
        const Mat3 D = p / 6.0 * skew(x.col(t[(j + 2) % 3]) - x.col(t[(j + 1) % 3]));
        for (int i = 0; i < 3; ++i)
          for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) {
              const Index slot = s[(3 * i + r) * 9 + 3 * j + c];
              if (slot >= 0) values[slot] += D(r, c);
            }
      }
    }
  }
}

void RayleighDamping::add_matrix(const ElasticAssembly& a, const Eigen::VectorXd& mass, const Points& x, double scale,
                                 double* values) const {
  const Pattern& p = a.pattern();
  if (alpha != 0.0)
    for (int f = 0; f < a.dofs().num_free(); ++f)
      for (int d = 0; d < 3; ++d)
        values[p.find(3 * Index(f) + d, 3 * Index(f) + d)] += scale * alpha * mass[a.dofs().free_nodes[f]];
  if (beta != 0.0) a.add_hessian(x, scale * beta, values);
}

std::vector<Spring> surface_springs(const Points& x, const std::vector<Tri>& surface) {
  std::map<std::pair<int, int>, std::vector<int>> opposite;  // edge -> vertices opposite it
  std::map<int, std::set<int>> nbr;
  for (const Tri& t : surface)
    for (int e = 0; e < 3; ++e) {
      int a = t[e], b = t[(e + 1) % 3];
      opposite[{std::min(a, b), std::max(a, b)}].push_back(t[(e + 2) % 3]);
      nbr[a].insert(b);
      nbr[b].insert(a);
    }
  std::set<std::pair<int, int>> made;
  std::vector<Spring> springs;
  auto add = [&](int a, int b, Spring::Kind k) {
    if (a == b) return;
    auto key = std::make_pair(std::min(a, b), std::max(a, b));
    if (!made.insert(key).second) return;
    springs.push_back({key.first, key.second, (x.col(a) - x.col(b)).norm(), k});
  };
  for (const auto& [e, opp] : opposite) add(e.first, e.second, Spring::structural);
  for (const auto& [e, opp] : opposite)
    if (opp.size() == 2) add(opp[0], opp[1], Spring::shear);
  for (const auto& [b, ns] : nbr)
    for (int a : ns) {
      const Vec3 d = (x.col(b) - x.col(a)).normalized();
      int best = -1;
      double best_cos = 0.5;
      for (int c : ns) {
        if (c == a) continue;
        const double cs = d.dot((x.col(c) - x.col(b)).normalized());
        if (cs > best_cos) best_cos = cs, best = c;
      }
      if (best >= 0) add(a, best, Spring::bending);
    }
  return springs;
}

}  // namespace isochor
