// Statics with KINSOL: for each frame's (pseudo-)time t, unknowns (q, lambda) with
//   -f(q, 0, t) + G^T lambda = 0,   g(q, t) = 0,
// Newton with a line search, KKT Jacobian [K + sum lambda_j H_j, G^T; G, 0] in a pattern built
// once and factored by KLU (linear_solver "klu"), or reduced to its n x n block A = K + sum
// lambda_j H_j with the constraint borders by a Schur complement: A factored by CHOLMOD
// ("reduced") or solved by block-Jacobi PCG ("krylov", A positive definite only). Each frame starts from the previous
// solution, so drivers that move with t apply their displacement in increments.
#pragma once
#include <memory>
#include <string>

#include "isochor/integrators/constrained_system.hpp"
#include "isochor/integrators/integrator.hpp"

namespace isochor {

struct StaticOptions {
  double residual_tol = 1e-9;  // KINSOL's scaled residual norm (forces over the system's force scale)
  long max_iterations = 200;   // Newton iterations per frame
  LinearSolverKind linear_solver = LinearSolverKind::klu;
  // A load increment (frame to frame) that fails is solved as two halves from the last
  // equilibrium, each halved again on failure, up to this many levels (0: the frame fails).
  int substeps_on_failure = 0;
};

// linear_solver = "auto" for statics: klu, or reduced where its border is the sparse one (more
// than 64 constraint rows on a system of 3-dof nodes). Measured in statics.cpp.
LinearSolverKind automatic_static_solver(const ConstrainedSystem& system);

class StaticSolver : public SteppingIntegrator {
 public:
  StaticSolver(ConstrainedSystem& system, StaticOptions options);
  ~StaticSolver() override;
  // Solves at every frame time; the frame sample's `newton_iterations` is cumulative, and
  // `step_size` holds the final scaled residual norm of that frame's solve.
  RunStats run(const std::vector<double>& frame_times, const FrameCallback& on_frame) override;
  // begin solves frame 0; step(t_out) solves the frames up to the first at or after t_out (the
  // time reached is the last frame solved); finish releases KINSOL.
  void begin(const std::vector<double>& frame_times, const FrameCallback& on_frame) override;
  double step(double t_out) override;
  RunStats finish() override;

  struct Impl;  // public so that the C callbacks can reach it

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace isochor
