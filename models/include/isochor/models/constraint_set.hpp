// A set of scalar constraints g_j(x, t) = 0 on a mesh's nodes, as a model's ConstrainedSystem
// stacks them: each set supplies its rows' values, their sparse gradients over the free dofs (a
// fixed pattern per row), dg/dt from the driven nodes' velocities, the rows of d(G v + dg/dt)/dq,
// and the contracted Hessian sum_j w_j H_j filled into the assembly pattern. Zone volumes and the
// volume a closed surface encloses (VolumeConstraints, constraints.hpp) are the sets there are; a
// new kind of constraint (contact as a constraint, surface area) implements this and is added to
// MeshSystem's list. Pointers address this set's rows within the stacked arrays.
#pragma once
#include <Eigen/Core>
#include <vector>

#include "isochor/models/assembly.hpp"

namespace isochor {

class ConstraintSet {
 public:
  virtual ~ConstraintSet() = default;
  virtual int size() const = 0;
  // Row j's free dof indices (sorted, fixed for the run).
  virtual const std::vector<Index>& row_dofs(int j) const = 0;
  // Typical size of g_j (a zone's rest volume), so that solvers measure it relative to that.
  virtual double scale(int j) const = 0;
  // Called when the time changes, before any of the below (for rows prescribed in time).
  virtual void set_time(double /*t*/) {}
  // g[0 .. size()) = g_j(x).
  virtual void value(const Points& x, double* g) const = 0;
  // rows[j] (layout of row_dofs(j)) = dg_j/dq.
  virtual void gradient(const Points& x, std::vector<double>* rows) const = 0;
  // gt[j] = dg_j/dt: the driven nodes' part of dg_j/dx . xdot (xdot: every node, 3 N).
  virtual void time_derivative(const Points& x, const Eigen::VectorXd& xdot, double* gt) const = 0;
  // rows[j] = (H_j xdot)^T at the free dofs, xdot the velocity of every node: d(G v + dg/dt)/dq.
  virtual void hessian_times(const Points& x, const Eigen::VectorXd& xdot, std::vector<double>* rows) const = 0;
  // values[slot] += scale sum_j w[j] H_j over the free dofs.
  virtual void add_hessian(const Points& x, const double* w, double scale, double* values) const = 0;
  // Per-tet pressure from the multipliers (p_e -= lambda_j for a zone j holding tet e); none by default.
  virtual void add_pressure(const double* /*lambda*/, std::vector<double>& /*p*/) const {}
};

}  // namespace isochor
