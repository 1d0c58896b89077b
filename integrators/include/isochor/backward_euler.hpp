// Backward Euler with a fixed step h, the time stepping of the CNH paper: per step the KKT system
//   M (q - q_n - h v_n) / h^2 - f(q, (q - q_n)/h, t) + G^T lambda = 0,   g(q, t) = 0,
// solved by Newton with the matrix [M/h^2 + K + D/h + sum lambda_j H_j, G^T; G, 0]
// (K = -df/dq, D = -df/dv), the symmetric block by CHOLMOD and the m borders by a Schur
// complement; a factorisation is reused while Newton contracts fast. "Semi-implicit": exactly one
// Newton iteration per step, from q = q_n + h v_n, with a fresh matrix.
#pragma once
#include <memory>

#include "isochor/ida_integrator.hpp"

namespace isochor {

struct BackwardEulerOptions {
  double dt = 1e-3;
  bool semi_implicit = false;
  bool rescale_volume = false;  // after each step, the system's naive volume rescaling
  int max_newton = 30;
  double newton_tol = 1e-8;  // Newton stops when |dq|_inf <= newton_tol * max(1, |q_n|_inf) (m)
  long max_steps = 100000000;
  // Up to this many constraints: CHOLMOD on the n x n step matrix and a dense Schur complement
  // for the borders; more (e.g. 1-ring zones): KLU on the whole (n + m) KKT matrix.
  int schur_max_constraints = 32;
  // "reduced" (the above), "klu" (KLU on the KKT matrix always), "krylov" (block-Jacobi PCG
  // instead of CHOLMOD on the step matrix; the KKT path above schur_max_constraints stays KLU).
  std::string linear_solver = "reduced";
};

class BackwardEuler {
 public:
  BackwardEuler(ConstrainedSystem& system, BackwardEulerOptions options);
  ~BackwardEuler();
  // Steps from frame_times.front(); frames between steps are interpolated linearly. Throws
  // IntegrationError (time, reason) after delivering every frame reached.
  IdaStats run(const std::vector<double>& frame_times, const FrameCallback& on_frame);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace isochor
