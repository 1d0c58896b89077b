// IDA's modified Newton iteration for a linear solver that can keep its matrix across setups
// (krylov with jacobian_age: a setup that only moves the kept Jacobian to the new c_j,
// ReducedSolver::retarget). It is IDA's own iteration and convergence test (SUNDIALS 6: residual,
// optional setup, up to max_iters corrections; the predicted error ss |delta| with
// ss = rate / (1 - rate); ss = 100 whenever c_j changed, 20 after a setup that assembled a new
// matrix) with two differences: a setup that kept the matrix leaves ss as it was, and a kept
// matrix is not current, so a recoverable failure with it earns one retry with a fresh setup.
//
// Keeping the rate estimate across changes of c_j too would save the second iteration on steps
// whose size changed, but a rate measured right after a fresh setup, where Newton converges
// fastest, then accepts later steps after one iteration on an older matrix: measured so, the
// pendulum of the MEBDFDAE test set lost 0.9 digit at rtol 1e-10 against every other solver
// (docs/results/tolerance.md).
#pragma once
#include <sundials/sundials_nonlinearsolver.h>

#include <functional>

namespace isochor {

// What the iteration asks of the integration that owns the linear solver.
struct IdaNewtonHooks {
  // Called before each setup: true when it follows a failed attempt with the old matrix (the
  // Jacobian must then be assembled afresh, not reused).
  std::function<void(bool)> before_setup;
  // After a setup: whether it kept the matrix (the same stiffness, moved to the new c_j), so that
  // the rate estimate stays valid.
  std::function<bool()> kept_matrix;
};

// A new nonlinear solver for IDASetNonlinearSolver (its vectors cloned from y); the caller frees
// it with SUNNonlinSolFree after IDAFree.
SUNNonlinearSolver make_ida_newton(N_Vector y, SUNContext ctx, IdaNewtonHooks hooks);

}  // namespace isochor
