// Backward Euler with a fixed step h, the time stepping of the CNH paper: per step the KKT system
//   M (q - q_n - h v_n) / h^2 - f(q, (q - q_n)/h, t) + G^T lambda = 0,   g(q, t) = 0,
// solved by Newton with the matrix [M/h^2 + K + D/h + sum lambda_j H_j, G^T; G, 0]
// (K = -df/dq, D = -df/dv), the symmetric block by CHOLMOD and the m borders by a Schur
// complement; a factorisation is reused while Newton contracts fast (rate below 1/4). Newton stops
// on its estimated error (contraction rate r: r / (1 - r) |dq|, the rate measured on the current
// matrix within the step) relative to the step's displacement; a first update on a matrix stops
// it only when the multipliers barely moved and the step's residual at the new q confirms it.
// "Semi-implicit": exactly one Newton iteration per step, from q = q_n + h v_n, with a fresh
// matrix. Step k ends at t0 + k h.
//
// As an optimisation (line_search, the default where the system has a potential): the step
// minimises the incremental potential
//   Phi(q) = |q - q_n - h v_n|^2_M / (2 h^2) + V(q) [+ (q - q_n)^T Dn (q - q_n) / (2 h) - fd0 . (q - q_n)]
// subject to g(q, t) = 0, whose stationary points are exactly the steps above. Each Newton
// direction is cut back (Armijo, halving) until the exact l1 merit Phi + sum_j nu_j |g_j|
// (nu_j = 2 |lambda_j|) decreases; a direction that does not descend, or a matrix that cannot be
// factored, is retried with the inertia term M / h^2 of the matrix scaled up (a
// Levenberg-Marquardt shift in the mass metric). Where the scene damps, the damping is made
// variational: its matrix Dn = -df/dv is frozen per step at the step's start q_n, with fd0 the
// damping force of the
// driven nodes' motion there, the bracketed terms; Rayleigh's beta K(q) v, re-evaluated at every
// iterate, is no gradient, and Newton's Jacobian lacks its dK/dq v term. project_hessian fills
// the matrix with every element's Hessian projected to be positive semi-definite (the residual
// stays exact). A failed step may be retried as two half steps, up to substeps_on_failure times.
#pragma once
#include <functional>
#include <memory>

#include "isochor/integrators/constrained_system.hpp"
#include "isochor/integrators/integrator.hpp"

namespace isochor {

struct BackwardEulerOptions {
  double dt = kDefaultFixedStep;
  bool semi_implicit = false;
  bool rescale_volume = false;  // after each step, the system's naive volume rescaling
  int max_newton = 30;
  // Newton stops when its estimated error in q is below newton_tol |q - q_n|_inf + newton_atol:
  // newton_tol is relative to the step's displacement (the velocity's relative accuracy),
  // newton_atol (m) the floor for a body at rest.
  double newton_tol = 1e-6;
  double newton_atol = 1e-12;
  long max_steps = kDefaultMaxSteps;
  // Up to this many constraints: the n x n step matrix by its solver (CHOLMOD or PCG) and a dense
  // Schur complement for the borders (m + 1 solves per Newton iteration); more: the whole (n + m)
  // KKT matrix by KktFactor (KLU, UMFPACK above 32 rows). Measured on the clamped beam (backward
  // Euler, 50 steps, the global zone and patches of 2 to 6 rings; bench/dense_border.sh, medians
  // of 3 rounds on one thread; docs/results/zones_cost.md): the dense border costs about 0.087 s
  // per row at 6,480 tets and 0.40 s at 21,870, the KKT path 0.012 and 0.098 per row over a fixed
  // 0.67 and 4.1 s: they cross near 4 rows on the first mesh and near 9 on the second; at 32 rows
  // the dense border took 3.0 and 1.9 times the KKT path's time. On MPI ranks (the KKT
  // matrix is one process's) the dense border goes up to kRanksDenseBorderMax whatever this is.
  // Scene key integrator.dense_border_rows.
  int schur_max_constraints = kDefaultDenseBorderRows;
  static constexpr int kDefaultDenseBorderRows = 8;
  static constexpr int kRanksDenseBorderMax = 32;
  // "reduced" (the above), "klu" (the KKT matrix always), "krylov" (block-Jacobi PCG instead of
  // CHOLMOD on the step matrix; the KKT path above schur_max_constraints stays KktFactor).
  LinearSolverKind linear_solver = LinearSolverKind::reduced;
  // krylov and amg: the relative residual at which CG stops (0: kDefaultLinearTol). Newton's
  // test measures its own contraction and stops on its estimated error, so an inexact solve
  // (relative residual eta < 1: a descent direction, linear convergence at a rate ~eta) moves the
  // work between CG and Newton, not the accuracy of a step.
  double linear_tol = 0.0;
  static constexpr double kDefaultLinearTol = 1e-4;
  // linear_solver = "auto" (backward Euler): block-Jacobi PCG ("krylov") where the step is
  // solved with the line search (a matrix PCG finds indefinite is shifted, never a failure) and
  // the step matrix has at least kAutoKrylovMinDofs rows; else CHOLMOD ("reduced"). Measured on
  // the pinned cube (docs/decisions.md): the two tie at 1,344 dofs (7^3 cells),
  // PCG is 1.4 times faster at 7,644 (13^3) and some 5 times at 57K (26^3). With the line search
  // the run then moves between PCG and CHOLMOD by a cost estimate from counts (for
  // stiff materials, where CG needs hundreds of iterations and one factor serves many steps;
  // backward_euler.cpp, after_step).
  bool automatic_linear_solver = false;
  static constexpr long kAutoKrylovMinDofs = 1300;
  // The step as a minimisation (above); off: plain Newton on the KKT system.
  bool line_search = true;
  bool project_hessian = false;
  // With project_hessian and the line search ("hybrid"): once two Newton updates in a row are
  // taken whole, the rest of the step uses the exact Hessian (quadratic convergence near the
  // solution, where the projected one contracts linearly, slowly where elements are indefinite).
  bool exact_near_solution = false;
  // Keep a factored step matrix across iterations and steps while it serves (backward_euler.cpp:
  // the contraction rate, and the reuse's cost against a fresh matrix's); off: a fresh matrix at
  // every Newton iteration (exact Newton), the reference the reuse is tested against.
  bool reuse_matrices = true;
  // A failed step is retried as two half steps, each of which may be halved again, up to this
  // many levels (0: a failed step stops the run).
  int substeps_on_failure = 0;
  // Called after each line search with the merit at the iterate and at the point accepted
  // (same weights), and the step length taken: for tests and diagnostics.
  std::function<void(double before, double after, double alpha)> on_line_search;
};

class BackwardEuler : public SteppingIntegrator {
 public:
  BackwardEuler(ConstrainedSystem& system, BackwardEulerOptions options);
  ~BackwardEuler() override;
  // Steps from frame_times.front(); frames between steps are interpolated linearly and projected
  // onto the constraints (initial_state.hpp: project_state). Throws
  // IntegrationError (time, reason) after delivering every frame reached.
  RunStats run(const std::vector<double>& frame_times, const FrameCallback& on_frame) override;
  void begin(const std::vector<double>& frame_times, const FrameCallback& on_frame) override;
  double step(double t_out) override;
  RunStats finish() override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace isochor
