// Hong et al. 2006's volume-preserving mass-spring model as a ConstrainedSystem: only the surface
// nodes of the mesh move (the unknowns are its free surface nodes); structural, shear and bending
// springs of one stiffness k with dashpots c along them; gravity and contact planes; one
// constraint, the volume enclosed by the surface (divergence theorem) equal to its rest value.
// The surface nodes' masses share the body's mass in proportion to their surface area. Interior
// nodes are not simulated; for output they follow the surface (each moves with the inverse-
// distance average of its nearest surface nodes' displacements), driven or not.
#pragma once
#include <memory>

#include "isochor/models/assembly.hpp"
#include "isochor/integrators/constrained_system.hpp"
#include "isochor/models/constraints.hpp"
#include "isochor/models/forces.hpp"
#include "isochor/scene/scene.hpp"
#include "isochor/scene/scene_system.hpp"
#include "isochor/models/supports.hpp"

namespace isochor {

class MassSpringSystem : public SceneSystem {
 public:
  explicit MassSpringSystem(const Scene& scene);

  int num_dofs() const override { return 3 * dofs_.num_free(); }
  // The enclosed volume (row 0, unless material.volume_constraint = false), then the supports
  // that hold some components of surface nodes.
  int num_constraints() const override { return static_cast<int>(rows_.size()); }
  int volume_rows() const { return constrained_ ? 1 : 0; }
  const VectorXd& mass() const override { return dof_mass_; }
  const SparsePattern& pattern() const override { return pattern_; }
  const std::vector<std::vector<Index>>& constraint_rows() const override { return rows_; }
  void initial_state(double t0, VectorXd& q, VectorXd& v) override;
  void force(double t, const VectorXd& q, const VectorXd& v, VectorXd& f) override;
  void add_force_jacobians(double t, const VectorXd& q, const VectorXd& v, double* neg_dfdq, double* neg_dfdv) override;
  void constraint(double t, const VectorXd& q, VectorXd& g) override;
  void constraint_jacobian(double t, const VectorXd& q, std::vector<std::vector<double>>& G, VectorXd* g_t) override;
  void add_constraint_hessian(double t, const VectorXd& q, const VectorXd& w, double scale, double* values) override;
  void constraint_velocity_jacobian(double t, const VectorXd& q, const VectorXd& v,
                                    std::vector<std::vector<double>>& rows) override;
  std::vector<double> breakpoints() const override { return scene_.breakpoints(); }
  double force_scale() const override { return force_scale_; }
  double constraint_scale(int j) const override { return j < volume_rows() ? rest_volume_ : supports_->scale(0); }

  // Diagnostics at a state, as MeshSystem's: every node's position (interior ones carried).
  void set_state(double t, const VectorXd& q, const VectorXd& v) override;
  const Points& positions() const override { return x_; }
  const Eigen::VectorXd& velocities() const override { return xdot_; }
  bool has_contact() const override { return external_->has_contact(); }
  void contact(Points& out) const override { external_->contact_forces(x_, &xdot_, out); }
  void collider_poses(std::vector<double>& out) const override { external_->pose_numbers(out); }
  void collider_scales(std::vector<double>& out) const override { external_->scale_numbers(out); }
  std::array<double, 3> energies() const override;  // kinetic, springs, external
  std::vector<double> volumes() const override;     // the enclosed volume (no zones)
  const DofMap& dofs() const override { return dofs_; }
  bool has_tets() const override { return false; }
  // Hong's weight vector (their eq. 15) per free surface node, summing to their number.
  Eigen::VectorXd weights(const Eigen::Vector3d& center, double radius) const;

 private:
  void place(double t, const VectorXd& q);                     // free and driven nodes
  void place(double t, const VectorXd& q, const VectorXd& v);  // and their velocities
  const Scene& scene_;
  DofMap dofs_;  // free = surface nodes not driven
  std::vector<Spring> springs_;
  std::vector<Index> spring_slots_;  // 36 per spring
  Pattern pattern_;
  std::unique_ptr<ExternalPotential> external_;
  VolumeConstraints volume_;
  std::unique_ptr<ComponentSupports> supports_;
  std::vector<std::vector<Index>> rows_;
  bool constrained_ = true;
  double k_, c_, rest_volume_, force_scale_ = 1.0;
  Eigen::VectorXd node_mass_, dof_mass_;
  std::vector<std::vector<std::pair<int, double>>> carry_;  // interior node -> (surface node, weight)
  Points x_;
  Eigen::VectorXd xdot_, grad_;
  double state_t_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace isochor
