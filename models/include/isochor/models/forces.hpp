// Forces other than elasticity: gravity, loads and contact with colliders (as a potential), Rayleigh damping,
// and the spring network of the mass-spring model.
#pragma once
#include <memory>
#include <vector>

#include "isochor/models/assembly.hpp"
#include "isochor/models/colliders.hpp"
#include "isochor/models/self_contact.hpp"

namespace isochor {

// How a load grows in time (statics: pseudo-time): min(1, t / ramp) (ramp = 0: full at once), or
// piecewise linear through (times, factors), held outside them.
struct LoadHistory {
  double ramp = 0.0;  // s
  std::vector<double> times, factors;
  double factor(double t) const;
  // Where the factor is not smooth: the ramp's end, every key.
  void breakpoints(std::vector<double>& out) const;
};

// A dead load on nodes ([[load]]): a fixed force on each node (N), from a point load or a
// traction on a surface, times its history's factor.
struct NodeLoad {
  std::vector<int> nodes;
  std::vector<Vec3> force;  // per node
  LoadHistory history;
};

// A pressure on surface triangles ([[load]] kind = "pressure"): a follower load, normal to the
// deformed surface. On a triangle (x0, x1, x2) with area vector a = (x1 - x0) x (x2 - x0) / 2
// (outward for the mesh's counter-clockwise surface triangles), each corner gets f = -p s(t) a / 3
// (s the history's factor):
// p > 0 pushes into the body. Its Jacobian d f_i / d x_j = -p s / 6 skew(x_(j+2) - x_(j+1))
// (indices mod 3) is not symmetric on an open surface: exact with KLU (the default of IDA and
// statics), approximated by its symmetric use in the reduced and krylov solvers. Not an energy in
// general, so it is left out of the external energy written per frame.
struct PressureLoad {
  std::vector<Tri> faces;
  double pressure = 0.0;  // Pa
  LoadHistory history;
};

class PressureLoads {
 public:
  PressureLoads(std::vector<PressureLoad> loads, const DofMap& dofs, const Pattern& pattern);
  bool empty() const { return loads_.empty(); }
  void set_time(double t) { time_ = t; }
  // grad += -f over every node (3 N).
  void add_gradient(const Points& x, Eigen::VectorXd& grad) const;
  // values += -df/dx over the free dofs (pattern slots).
  void add_jacobian(const Points& x, double* values) const;

 private:
  std::vector<PressureLoad> loads_;
  std::vector<std::vector<Index>> slots_;  // per load, 81 per face
  double time_ = 0.0;
};

// Gravity, dead loads and the colliders (the ground among them) as one external potential:
// sum_i -m_i g . x_i - sum_loads f_i . x_i + contact energy; the colliders' damping and friction
// as a dissipative force beside it.
class ExternalPotential {
 public:
  // area: each node's rest surface area (per-area contact laws; empty if none is per area).
  // skeleton: the scene's, if a collider rides a bone.
  ExternalPotential(Eigen::VectorXd mass, Vec3 gravity, std::vector<Collider> colliders, const DofMap& dofs,
                    const Pattern& pattern, Eigen::VectorXd area = {}, std::shared_ptr<const Skeleton> skeleton = {});
  double energy(const Points& x) const;
  // grad += gradient over every node (3 N).
  double add_gradient(const Points& x, Eigen::VectorXd& grad) const;
  // values += scale * Hessian over the free dofs (the contact's 3x3 diagonal blocks).
  void add_hessian(const Points& x, double scale, double* values) const;
  const Eigen::VectorXd& mass() const { return mass_; }
  // Gravity is multiplied by this factor (loads applied in increments); 1 by default.
  void set_gravity_scale(double s) { gravity_scale_ = s; }
  // Moves the colliders to where they are at time t, and scales the loads.
  void set_time(double t);
  void set_loads(std::vector<NodeLoad> loads) { loads_ = std::move(loads); }
  // grad += -(the loads' forces) at the current time; returns their potential -f . x.
  double add_load_gradient(Eigen::VectorXd& grad, const Points* x = nullptr) const;
  // The colliders' damping and friction: grad += -f (every node, 3 N), for velocities xdot (3 N).
  void add_damping(const Points& x, const Eigen::VectorXd& xdot, Eigen::VectorXd& grad) const;
  // -df/dx and -df/dv of the damping and friction over the free dofs (either may be null).
  void add_damping_jacobians(const Points& x, const Eigen::VectorXd& xdot, double* neg_dfdx, double* neg_dfdv) const;
  bool damped() const { return damped_; }
  bool has_friction() const { return friction_; }
  bool has_contact() const { return !colliders_.empty() || self_; }
  // Contact between parts of the body (self_contact.hpp): in the energy, gradient, Hessian and
  // contact forces from now on.
  void set_self_contact(std::unique_ptr<SelfContact> s) {
    self_ = std::move(s);
    damped_ = damped_ || self_->damped();
  }
  // The force of every collider on every node (N, 3 x N): the contact's elastic force, plus its
  // damping and friction for velocities xdot (if given).
  void contact_forces(const Points& x, const Eigen::VectorXd* xdot, Points& out) const;
  // The poses as 12 numbers each: A row-major, then b.
  void pose_numbers(std::vector<double>& out) const;
  // Each collider's radius factor at the current time (Frame::collider_scales).
  void scale_numbers(std::vector<double>& out) const;

 private:
  Vec3 g() const { return gravity_scale_ * gravity_; }
  // Calls f(node, k, s, n, H) for every node (every free node if free_only) within collider c's
  // contact thickness.
  template <class F>
  void for_each_contact(std::size_t c, const Points& x, bool free_only, F&& f) const;
  Eigen::VectorXd mass_;
  Vec3 gravity_;
  double gravity_scale_ = 1.0;
  std::vector<Collider> colliders_;
  std::vector<ColliderPose> poses_;  // where each collider is now
  std::shared_ptr<const Skeleton> skeleton_;
  std::unique_ptr<SelfContact> self_;
  std::vector<NodeLoad> loads_;
  double time_ = 0.0;
  bool damped_ = false, friction_ = false;
  DofMap dofs_;
  std::vector<Index> diag_slots_;  // 9 per free node
  Eigen::VectorXd area_;
  double stiffness(std::size_t c, int node) const {
    return colliders_[c].law.per_area ? colliders_[c].law.stiffness * area_[node] : colliders_[c].law.stiffness;
  }
};

// Rayleigh damping f = -(alpha M + beta K(x)) v. Its derivative by v is -(alpha M + beta K); the
// derivative through K(x) (a third derivative of the energy) is left out of Jacobians.
struct RayleighDamping {
  double alpha = 0.0, beta = 0.0;
  // The force -(alpha M + beta K) v is computed in MeshSystem's element pass (beta K v beside the
  // elastic gradient), not here.
  // values += scale * (alpha M + beta K) over the free dofs.
  void add_matrix(const ElasticAssembly& a, const Eigen::VectorXd& mass, const Points& x, double scale,
                  double* values) const;
};

// Springs of the mass-spring model on a closed triangle surface, after Hong et al. (2006) and
// Choi and Ko: structural springs on the edges; shear springs across each edge, between the two
// vertices opposite it (the other diagonal of the two triangles); bending springs between
// secondary neighbours a - b - c along the straightest continuation of each edge (cos > 0.5).
struct Spring {
  int a, b;
  double rest_length;
  enum Kind { structural, shear, bending } kind;
};
std::vector<Spring> surface_springs(const Points& x, const std::vector<Tri>& surface);

}  // namespace isochor
