// IDA's Newton iteration with a convergence test that keeps its rate estimate across a change of
// c_j, for a linear solver that follows c_j exactly (ReducedSolver::retarget).
//
// IDA's own test (SUNDIALS 6) predicts the error left after an iteration from the contraction
// rate seen so far, ss = rate / (1 - rate), and accepts when ss |delta| <= tol. Whenever c_j
// differs from the last step's, IDA sets ss = 100, since its linear solver still holds the old
// c_j and the rate seen before says nothing about the new matrix. That forces a second Newton
// iteration on every step whose size or order changed (16% of the 16^3 collapse's steps). When
// the solves follow c_j exactly, the rate is that of the stale stiffness alone, which a change
// of c_j hardly moves, and this iteration keeps it (where the solver does not follow, it resets as
// IDA does). Otherwise it is IDA's modified Newton:
// residual, optional setup, up to max_iters corrections, one retry with a fresh setup after a
// recoverable failure on a stale one; ss = 20 after each setup that assembled a new matrix, as IDA
// does after every setup.
#pragma once
#include <sundials/sundials_nonlinearsolver.h>

#include <functional>

namespace isochor {

// What the iteration asks of the integration that owns the linear solver.
struct IdaNewtonHooks {
  // Whether the next linear solve will be at IDA's current c_j; where it is not (e.g. a direct
  // fallback), a changed c_j resets the rate estimate as IDA's own test does.
  std::function<bool()> follows_cj;
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
