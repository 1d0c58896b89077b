// The stabilised index-2 (Gear-Gupta-Leimkuhler) DAE of a ConstrainedSystem integrated by
// SUNDIALS IDA (variable-order BDF), the Newton systems solved on a Jacobian whose pattern is
// built once (ggl.hpp):
//   F_q  = q' - v + G^T mu          F_v  = M v' - f(q, v, t) + G^T lambda
//   F_g  = g(q, t)                  F_gv = G v + dg/dt
// lambda and mu are algebraic and kept out of IDA's error test. IDA steps freely: its steps end
// only at the system's breakpoints (a driver's kink) and the last frame; each frame is IDA's
// interpolated state (IDAGetDky) projected back onto g = 0 and G v + dg/dt = 0
// (initial_state.hpp: project_state), so every frame holds the constraints to rounding.
#pragma once
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "isochor/integrators/constrained_system.hpp"
#include "isochor/integrators/integrator.hpp"

namespace isochor {

// Tolerances (each settable from the scene, docs/scenes.md):
//   positions    rtol and atol_q (m): IDA's error test on q;
//   velocities   rtol and atol_v (m/s): IDA's error test on v; 0 stands for 100 atol_q per
//                second, which caps the accuracy of v at tight rtol unless set;
//   multipliers  atol_lambda, seen only by Newton's convergence test (they are algebraic); 0
//                stands for 1e-6 of the system's force scale;
//   constraints  held by Newton at every step to IDA's nonlinear tolerance (newton_coef of the
//                error test's tolerance).
struct IdaOptions {
  double rtol = 1e-6;
  double atol_q = 1e-8;
  double atol_v = 0.0;
  double atol_lambda = 0.0;
  int max_order = 5;
  double max_step = 0.0;  // 0: no limit
  // IDA's nonlinear convergence coefficient: Newton stops once its predicted error is below this
  // fraction of the error test's tolerance (smaller: algebraic rows kept tighter); 0:
  // kDefaultNewtonCoef for every linear solver. Measured on the test DAEs (the MEBDFDAE pendulum,
  // the car axis; docs/results/tolerance.md): at IDA's 0.33 the Newton error, left up to a third
  // of the local error, moves the error estimates and so the steps, and the solvers' errors
  // differed by up to 0.13 digits on their fitted lines (0.35-0.9 at single tolerances); at 0.05
  // they agree within 0.08, each solver with fewer Newton iterations and steps in total.
  double newton_coef = 0;
  static constexpr double kDefaultNewtonCoef = 0.05;
  int max_newton = 4;         // Newton iterations per step attempt before IDA calls it a failure (IDASetMaxNonlinIters)
  double initial_step = 0.0;  // 0: a position-based first step (see the .cpp)
  long max_steps = kDefaultMaxSteps;  // over the whole run
  // End a step on every frame time too (IDASetStopTime), as before frames were interpolated: for
  // comparisons; it costs steps and holds IDA at low order when frames are dense.
  bool stop_at_frames = false;
  KluOrdering ordering = KluOrdering::metis;
  LinearSolverKind linear_solver = LinearSolverKind::klu;
  // Reuse the last assembled Jacobian (with the current c_j) for setups within this many steps of
  // it, unless Newton failed since; 0: assemble at every setup.
  long jacobian_age = 0;
  // Relative residual at which CG stops (linear solvers krylov and amg); 0: min(1e-12, 1e-6 rtol).
  double linear_tol = 0.0;
  // Called with every Jacobian IDA asks for (its values in the GGL form's pattern, ggl.hpp), e.g.
  // to test linear solvers on the matrices of a real integration.
  std::function<void(double t, double cj, const double* y, const double* yp, const double* values)> on_jacobian;
};

class IdaIntegrator : public SteppingIntegrator {
 public:
  IdaIntegrator(ConstrainedSystem& system, IdaOptions options);
  ~IdaIntegrator() override;
  RunStats run(const std::vector<double>& frame_times, const FrameCallback& on_frame) override;
  void begin(const std::vector<double>& frame_times, const FrameCallback& on_frame) override;
  double step(double t_out) override;
  RunStats finish() override;

  struct Impl;  // public so that the C callbacks can reach it

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace isochor
