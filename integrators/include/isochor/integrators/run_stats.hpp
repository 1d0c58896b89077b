// What every integrator returns and reports: run statistics (totals and a sample per frame), the
// frame callback, and the error of a failed integration (the time reached and the reason).
#pragma once
#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "isochor/base/error.hpp"

namespace isochor {

// Statistics of a run; per-frame series are sampled at each frame. Fields an integrator does not
// have stay 0 (XPBD reports its sweeps as newton_iterations).
struct RunStats {
  long steps = 0, residual_evals = 0, jacobian_evals = 0, linear_setups = 0, newton_iterations = 0, newton_failures = 0,
       error_test_failures = 0, fresh_factorisations = 0, reused_jacobians = 0;
  double wall_seconds = 0, assembly_seconds = 0, factor_seconds = 0, solve_seconds = 0;
  double factor_nnz = 0;          // nnz(L) + nnz(U) of the last factorisation
  long linear_iterations = 0;     // krylov: PCG iterations over the run
  long linear_fallbacks = 0;      // krylov: setups solved by CHOLMOD after PCG failed
  long retargets = 0;             // IDA krylov: setups moved to a new c_j (ReducedSolver::retarget)
  double symbolic_seconds = 0;    // of factor_seconds: ordering and symbolic analysis
  double projection_seconds = 0;  // IDA: projecting interpolated frames onto the constraints
  // Backward Euler as an optimisation: Newton iterations whose step the line search cut,
  // matrices shifted because they could not be factored or gave no descent, and steps
  // retried as half steps after a failure.
  long line_search_cuts = 0, regularisations = 0, step_halvings = 0;
  long solver_switches = 0;  // backward Euler, linear_solver = "auto": changes between PCG and CHOLMOD
  struct FrameSample {
    long steps, newton_iterations, error_test_failures, newton_failures, jacobian_evals;
    int order;
    double step_size;  // statics: the frame's final scaled residual norm
  };
  std::vector<FrameSample> frames;
};

// A failed integration: the time reached and the reason.
class IntegrationError : public Error {
 public:
  IntegrationError(double t, const std::string& reason)
      : Error("integration failed at t = " + std::to_string(t) + " s: " + reason), time(t) {}
  double time;

 protected:
  IntegrationError(const std::string& message, double t) : Error(message), time(t) {}
};

// A run stopped from outside (interrupt.hpp) at a step boundary at time t, by this signal.
class Interrupted : public IntegrationError {
 public:
  Interrupted(double t, int sig)
      : IntegrationError("interrupted by signal " + std::to_string(sig) + " at t = " + std::to_string(t) + " s", t),
        signal(sig) {}
  int signal;
};

// Called at each frame with the frame index, time, the state (q, v, lambda) and the solver's
// cumulative statistics at that frame.
using FrameCallback = std::function<void(int, double, const Eigen::VectorXd&, const Eigen::VectorXd&,
                                         const Eigen::VectorXd&, const RunStats::FrameSample&)>;

}  // namespace isochor
