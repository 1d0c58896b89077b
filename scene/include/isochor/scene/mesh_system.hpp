// A mesh scene as a ConstrainedSystem: free nodes are the unknowns, boundary nodes follow their
// drivers, forces are elasticity (the material, plus the epidermis), gravity, the ground and
// Rayleigh damping; the constraints are a list of ConstraintSets stacked in order (today the
// scene's zone volumes, none for an unconstrained model).
#pragma once
#include <memory>

#include "isochor/models/assembly.hpp"
#include "isochor/integrators/constrained_system.hpp"
#include "isochor/models/constraints.hpp"
#include "isochor/models/forces.hpp"
#include "isochor/scene/scene.hpp"
#include "isochor/scene/scene_system.hpp"

namespace isochor {

std::shared_ptr<const Material> make_material(const MaterialSpec& m);
// The scene's free and driven nodes, and the tets of each zone (in scene order).
DofMap scene_dofs(const Scene& s);
// The same with each rank's free nodes together, rank after rank (node_rank: each node's rank;
// empty: one process), and each node's rank from METIS's partition of the node graph.
DofMap scene_dofs(const Scene& s, const std::vector<int>& node_rank);
std::vector<int> scene_node_ranks(const Scene& s, int parts);
std::vector<std::vector<int>> scene_zone_tets(const Scene& s);
// The free nodes' rest positions and the scene's initial velocity, as (q, v) of the free dofs.
void scene_initial_state(const Scene& s, const DofMap& dofs, const StartState* start, VectorXd& q, VectorXd& v);
// What changes with time alone: driven nodes' positions and velocities, contact planes, gravity.
void scene_at_time(const Scene& s, double t, Points& x, Eigen::VectorXd& xdot, ExternalPotential& external);

class MeshSystem : public SceneSystem {
 public:
  // ranks (ranks.hpp): split the elements over them (null or one rank: one process).
  explicit MeshSystem(const Scene& scene, const Ranks* ranks = nullptr);

  int num_dofs() const override { return 3 * dofs_.num_free(); }
  int num_constraints() const override { return static_cast<int>(rows_.size()); }
  const VectorXd& mass() const override { return dof_mass_; }
  const SparsePattern& pattern() const override { return elastic_->pattern(); }
  const std::vector<std::vector<Index>>& constraint_rows() const override { return rows_; }
  void initial_state(double t0, VectorXd& q, VectorXd& v) override;
  void force(double t, const VectorXd& q, const VectorXd& v, VectorXd& f) override;
  void add_force_jacobians(double t, const VectorXd& q, const VectorXd& v, double* neg_dfdq, double* neg_dfdv) override;
  void force_and_jacobians(double t, const VectorXd& q, const VectorXd& v, VectorXd& f, double* neg_dfdq,
                           double* neg_dfdv) override;
  void constraint(double t, const VectorXd& q, VectorXd& g) override;
  void constraint_jacobian(double t, const VectorXd& q, std::vector<std::vector<double>>& G, VectorXd* g_t) override;
  void add_constraint_hessian(double t, const VectorXd& q, const VectorXd& w, double scale, double* values) override;
  void constraint_velocity_jacobian(double t, const VectorXd& q, const VectorXd& v,
                                    std::vector<std::vector<double>>& rows) override;
  std::vector<double> breakpoints() const override { return scene_.breakpoints(); }
  double force_scale() const override { return force_scale_; }
  bool rescale_volume(double t, VectorXd& q) override;
  bool potential(double t, const VectorXd& q, double& V) override;
  bool has_damping() const override { return damping_.alpha != 0 || damping_.beta != 0 || external_->damped(); }
  // Friction is not variational (its force is not the gradient of a dissipation frozen per step):
  // a scene with friction keeps its damping forces on, and backward Euler takes plain Newton steps.
  bool set_damping_forces(bool on) override {
    if (external_->has_friction()) return false;
    damping_on_ = on;
    return true;
  }
  bool set_hessian_projection(bool on) override {
    project_hessian_ = on;
    return true;
  }
  double constraint_scale(int j) const override { return row_scale_[j]; }
  const DofPartition* partition() const override { return partition_.ranks ? &partition_ : nullptr; }

  // Positions and velocities of every node (3 N) for a state of the unknowns at time t
  // (driven nodes from their drivers, evaluated once per distinct t).
  void set_state(double t, const VectorXd& q, const VectorXd& v) override;
  void set_positions(double t, const VectorXd& q);
  const Points& positions() const override { return x_; }
  const Eigen::VectorXd& velocities() const override { return xdot_; }
  // Kinetic, elastic and external energy at the current state.
  std::array<double, 3> energies() const override;
  // Total volume, then each zone's volume, at the current state.
  std::vector<double> volumes() const override;
  // Per-tet pressure at the current state for multipliers lambda.
  void pressures(const VectorXd& lambda, std::vector<double>& p) const override;
  bool has_tets() const override { return true; }
  int inverted_tets() const override { return elastic_->inverted_tets(x_); }
  bool has_loads() const override { return !scene_.loads.empty() || !pressure_loads_->empty(); }
  void loads(Points& out) const override;
  bool has_contact() const override { return external_->has_contact(); }
  void contact(Points& out) const override { external_->contact_forces(x_, &xdot_, out); }
  void collider_poses(std::vector<double>& out) const override { external_->pose_numbers(out); }
  void collider_scales(std::vector<double>& out) const override { external_->scale_numbers(out); }
  const DofMap& dofs() const override { return dofs_; }
  std::vector<double> activations() const override { return elastic_->activations(); }
  void set_activation_function(std::function<std::vector<double>(double)> f) override {
    activation_fn_ = std::move(f);
    state_t_ = std::numeric_limits<double>::quiet_NaN();
  }

 private:
  const Scene& scene_;
  std::vector<int> node_rank_;  // on P ranks: each node's rank (empty on one process)
  DofMap dofs_;
  DofPartition partition_;
  std::vector<Index> value_offsets_;  // each rank's columns in the pattern's values
  // On P ranks: each rank's rows of f and of the Jacobians to every rank.
  void share(VectorXd* f, double* neg_dfdq, double* neg_dfdv) const;
  // The elastic energy of the whole mesh (summed over the ranks).
  double elastic_energy() const;
  std::shared_ptr<const Material> material_;
  std::unique_ptr<ElasticAssembly> elastic_;
  std::unique_ptr<ExternalPotential> external_;
  std::unique_ptr<PressureLoads> pressure_loads_;
  RayleighDamping damping_;
  // The constraint sets, stacked: set s owns rows offset_[s] .. offset_[s + 1].
  std::vector<std::unique_ptr<ConstraintSet>> sets_;
  std::vector<int> offset_{0};
  VolumeConstraints zone_volumes_;  // every zone, kept or only measured (for volumes())
  std::vector<std::vector<Index>> rows_;
  std::vector<double> row_scale_;
  void add_constraints(std::unique_ptr<ConstraintSet> set);
  Eigen::VectorXd node_mass_, dof_mass_;
  double force_scale_ = 1.0;
  bool project_hessian_ = false;
  bool damping_on_ = true;  // set_damping_forces
  std::function<std::vector<double>(double)> activation_fn_;
  // State cache: positions and velocities of every node.
  Points x_;
  Eigen::VectorXd xdot_, grad_, kv_;
  double state_t_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace isochor
