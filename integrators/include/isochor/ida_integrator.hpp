// The stabilised index-2 (Gear-Gupta-Leimkuhler) DAE of a ConstrainedSystem integrated by
// SUNDIALS IDA (variable-order BDF) with KLU on a Jacobian whose pattern is built once:
//   F_q  = q' - v + G^T mu          F_v  = M v' - f(q, v, t) + G^T lambda
//   F_g  = g(q, t)                  F_gv = G v + dg/dt
// lambda and mu are algebraic and kept out of IDA's error test. Frames come from IDA's
// interpolant (IDA_ONE_STEP + IDAGetDky), never by shortening steps.
#pragma once
#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "isochor/constrained_system.hpp"

namespace isochor {

struct IdaOptions {
  double rtol = 1e-6;
  double atol_q = 1e-8;      // positions
  double atol_v = 0.0;       // velocities; 0: atol_q times 100 per second
  double atol_lambda = 0.0;  // multipliers (only the Newton test sees them); 0: from force_scale()
  int max_order = 5;
  double max_step = 0.0;     // 0: no limit
  double newton_coef = 0.33; // IDA's nonlinear convergence coefficient (smaller: algebraic rows kept tighter)
  double initial_step = 0.0; // 0: IDA's choice
  long max_steps = 10000000; // over the whole run
  std::string ordering = "metis";  // KLU: "metis" (node-grouped nested dissection), "colamd", "amd"
  // "klu": the whole GGL matrix; "reduced": eliminate dv, factor S with CHOLMOD (ggl.hpp).
  std::string linear_solver = "klu";
  // Reuse the last assembled Jacobian (with the current c_j) for setups within this many steps of
  // it, unless Newton failed since; 0: assemble at every setup.
  long jacobian_age = 0;
  // Called with every Jacobian IDA asks for (its values in the GGL form's pattern, ggl.hpp), e.g.
  // to test linear solvers on the matrices of a real integration.
  std::function<void(double t, double cj, const double* y, const double* yp, const double* values)> on_jacobian;
};

// Statistics of a run; per-frame series are sampled at each frame.
struct IdaStats {
  long steps = 0, residual_evals = 0, jacobian_evals = 0, linear_setups = 0, newton_iterations = 0,
       newton_failures = 0, error_test_failures = 0, fresh_factorisations = 0, reused_jacobians = 0;
  double wall_seconds = 0, assembly_seconds = 0, factor_seconds = 0, solve_seconds = 0;
  double factor_nnz = 0;  // nnz(L) + nnz(U) of the last factorisation
  long linear_iterations = 0;  // krylov: PCG iterations over the run
  long linear_fallbacks = 0;   // krylov: setups solved by CHOLMOD after PCG failed
  double symbolic_seconds = 0;  // of factor_seconds: ordering and symbolic analysis (CHOLMOD paths)
  struct FrameSample {
    long steps, newton_iterations, error_test_failures, newton_failures, jacobian_evals;
    int order;
    double step_size;
  };
  std::vector<FrameSample> frames;
};

// A failed integration: the time reached and IDA's reason.
class IntegrationError : public std::runtime_error {
 public:
  IntegrationError(double t, const std::string& reason)
      : std::runtime_error("integration failed at t = " + std::to_string(t) + " s: " + reason), time(t) {}
  double time;
};

// Called at each frame with the frame index, time, the state (q, v, lambda) and the solver's
// cumulative statistics at that frame.
using FrameCallback = std::function<void(int, double, const VectorXd&, const VectorXd&, const VectorXd&,
                                         const IdaStats::FrameSample&)>;

class IdaIntegrator {
 public:
  IdaIntegrator(ConstrainedSystem& system, IdaOptions options);
  ~IdaIntegrator();
  // Integrates from frame_times.front() to frame_times.back(). Throws IntegrationError after
  // delivering every frame reached.
  IdaStats run(const std::vector<double>& frame_times, const FrameCallback& on_frame);

  // The consistent initial state (exposed for tests): q on g = 0, v with G v + g_t = 0, and the
  // acceleration and multipliers of the index-1 system.
  static void consistent_initial_state(ConstrainedSystem& sys, double t0, VectorXd& q, VectorXd& v, VectorXd& a,
                                       VectorXd& lambda);

  struct Impl;  // public so that the C callbacks can reach it

 private:
  Impl* impl_;
};

}  // namespace isochor
