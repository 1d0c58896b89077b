// Backward Euler with a fixed step h, the time stepping of the CNH paper: per step the KKT system
//   M (q - q_n - h v_n) / h^2 - f(q, (q - q_n)/h, t) + G^T lambda = 0,   g(q, t) = 0,
// solved by Newton with the matrix [M/h^2 + K + D/h + sum lambda_j H_j, G^T; G, 0]
// (K = -df/dq, D = -df/dv), the symmetric block by CHOLMOD and the m borders by a Schur
// complement; a factorisation is reused while Newton contracts fast (rate below 1/4). Newton stops
// on its estimated error (contraction rate r: r / (1 - r) |dq|) relative to the step's
// displacement. "Semi-implicit": exactly one Newton iteration per step, from q = q_n + h v_n,
// with a fresh matrix. Step k ends at t0 + k h.
#pragma once
#include <memory>

#include "isochor/constrained_system.hpp"
#include "isochor/integrator.hpp"

namespace isochor {

struct BackwardEulerOptions {
  double dt = 1e-3;
  bool semi_implicit = false;
  bool rescale_volume = false;  // after each step, the system's naive volume rescaling
  int max_newton = 30;
  // Newton stops when its estimated error in q is below newton_tol |q - q_n|_inf + newton_atol:
  // newton_tol is relative to the step's displacement (the velocity's relative accuracy),
  // newton_atol (m) the floor for a body at rest.
  double newton_tol = 1e-6;
  double newton_atol = 1e-12;
  long max_steps = 100000000;
  // Up to this many constraints: CHOLMOD on the n x n step matrix and a dense Schur complement
  // for the borders; more (e.g. 1-ring zones): KLU on the whole (n + m) KKT matrix.
  int schur_max_constraints = 32;
  // "reduced" (the above), "klu" (KLU on the KKT matrix always), "krylov" (block-Jacobi PCG
  // instead of CHOLMOD on the step matrix; the KKT path above schur_max_constraints stays KLU).
  LinearSolverKind linear_solver = LinearSolverKind::reduced;
};

class BackwardEuler : public Integrator {
 public:
  BackwardEuler(ConstrainedSystem& system, BackwardEulerOptions options);
  ~BackwardEuler() override;
  // Steps from frame_times.front(); frames between steps are interpolated linearly. Throws
  // IntegrationError (time, reason) after delivering every frame reached.
  RunStats run(const std::vector<double>& frame_times, const FrameCallback& on_frame) override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace isochor
