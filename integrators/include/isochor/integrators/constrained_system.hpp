// What the integrators see of a model: positions q and velocities v of n free dofs, a lumped
// (diagonal) mass, forces f(q, v, t) and their Jacobians, and m scalar constraints g(q, t) = 0
// with their gradients G, time derivatives and contracted Hessians. Nothing here knows meshes,
// so a pendulum or a multibody test problem runs through the same integrators as a tet mesh.
//
// Sign convention of the multipliers, for every integrator: the equations of motion are
//   M v' = f(q, v, t) - G^T lambda,   g(q, t) = 0,
// so the constraint force is -G^T lambda, statics solves -f + G^T lambda = 0, and for a zone
// volume (G = dV/dq) lambda is the zone's pressure (positive when the zone is compressed).
//
// Every integrator checks the system first (initial_state.hpp: check_system): n must be a
// multiple of dofs_per_group(), the masses positive, the constraint rows within the dofs.
#pragma once
#include <Eigen/Core>
#include <vector>

#include "isochor/integrators/ranks.hpp"
#include "isochor/integrators/sparse_pattern.hpp"

namespace isochor {

using Eigen::VectorXd;

class ConstrainedSystem {
 public:
  virtual ~ConstrainedSystem() = default;

  virtual int num_dofs() const = 0;         // n
  virtual int num_constraints() const = 0;  // m
  // Dofs that belong together (a node's x, y, z): dof i is in group i / dofs_per_group(); a 2-D
  // system overrides it with 2. Orderings (METIS) work on these groups.
  virtual int dofs_per_group() const { return 3; }
  // Lumped mass of each dof (n), constant and positive.
  virtual const VectorXd& mass() const = 0;
  // Pattern of the n x n force Jacobians and constraint Hessians; holds every diagonal entry.
  virtual const SparsePattern& pattern() const = 0;
  // The dofs of each constraint row of G (sorted), fixed for the run.
  virtual const std::vector<std::vector<Index>>& constraint_rows() const = 0;

  // Positions and velocities at the start.
  virtual void initial_state(double t0, VectorXd& q, VectorXd& v) = 0;
  // Whether that start is an integrator's own state stored by an earlier run (a resume): it is
  // then taken as it is, not projected onto the constraints again (backward Euler's velocities
  // hold G v + dg/dt = 0 only to its step error, and a projection would change the run).
  virtual bool starts_from_stored_state() const { return false; }
  // With that stored state, its multipliers if they were stored too (else false): the Newton
  // iterations of the first step start from them, as an uninterrupted run's would.
  virtual bool stored_multipliers(VectorXd& /*lambda*/) const { return false; }
  // f(q, v, t), every force on the free dofs.
  virtual void force(double t, const VectorXd& q, const VectorXd& v, VectorXd& f) = 0;
  // neg_dfdq += -df/dq and neg_dfdv += -df/dv, both in pattern() (either may be null).
  virtual void add_force_jacobians(double t, const VectorXd& q, const VectorXd& v, double* neg_dfdq,
                                   double* neg_dfdv) = 0;
  // f and both Jacobians at once (a model may share work between them, e.g. one pass over its
  // elements); the same as force() then add_force_jacobians().
  virtual void force_and_jacobians(double t, const VectorXd& q, const VectorXd& v, VectorXd& f, double* neg_dfdq,
                                   double* neg_dfdv) {
    force(t, q, v, f);
    add_force_jacobians(t, q, v, neg_dfdq, neg_dfdv);
  }
  // g(q, t).
  virtual void constraint(double t, const VectorXd& q, VectorXd& g) = 0;
  // Rows of G (values in the layout of constraint_rows()) and, when asked, dg/dt.
  virtual void constraint_jacobian(double t, const VectorXd& q, std::vector<std::vector<double>>& G, VectorXd* g_t) = 0;
  // values += scale sum_j w_j H_j, H_j the Hessian of g_j by q, in pattern().
  virtual void add_constraint_hessian(double t, const VectorXd& q, const VectorXd& w, double scale, double* values) = 0;
  // Rows of d(G v + dg/dt)/dq (layout of constraint_rows()): (H_j xdot)^T with xdot the velocity of
  // every point the constraint depends on, driven ones included.
  virtual void constraint_velocity_jacobian(double t, const VectorXd& q, const VectorXd& v,
                                            std::vector<std::vector<double>>& rows) = 0;
  // The potential energy V(q) at time t whose gradient is minus the conservative forces
  // (elasticity, gravity, dead loads, contact), for the merit function of backward Euler's line
  // search. False if the system has none (a follower load has no potential); a non-finite V (an
  // element where its energy is not defined) is returned as it is.
  virtual bool potential(double /*t*/, const VectorXd& /*q*/, double& /*V*/) { return false; }
  // Fill force Jacobians with every element's Hessian projected onto the positive semi-definite
  // matrices (negative eigenvalues set to zero), the residual unchanged. False if the system
  // cannot (then the request is refused).
  virtual bool set_hessian_projection(bool /*on*/) { return false; }
  // Whether any force depends on the velocities (damping), and a switch that leaves those forces
  // out of force(), force_and_jacobians() and add_force_jacobians() (both Jacobians) until it is
  // turned back on; false if the system has no such switch. Backward Euler's line search freezes
  // the damping matrix per step with it (backward_euler.hpp).
  virtual bool has_damping() const { return false; }
  virtual bool set_damping_forces(bool /*on*/) { return false; }
  // Naive volume rescaling (the CNH paper's section 8.3 baseline): moves q so that the body's
  // total volume is its rest volume again, by scaling about the centre of mass. Returns false if
  // the model has no such operation.
  virtual bool rescale_volume(double /*t*/, VectorXd& /*q*/) { return false; }
  // Sorted times where f or g is not smooth in t (a driver's kink): steps of adaptive
  // integrators end there rather than step across.
  virtual std::vector<double> breakpoints() const { return {}; }
  // Typical size of a force, in force units, for the tolerances of the multipliers.
  virtual double force_scale() const { return 1.0; }
  // Typical size of constraint j's value (a zone's rest volume), so that solvers measure g_j
  // relative to it.
  virtual double constraint_scale(int /*j*/) const { return 1.0; }
  // On P ranks (ranks.hpp): the dofs each rank owns. The system then fills force() and the
  // Jacobians on every rank in full (each rank's rows shared with the others), and the
  // integrators' iterative solvers split their products by it. Null on one process.
  virtual const DofPartition* partition() const { return nullptr; }
};

}  // namespace isochor
