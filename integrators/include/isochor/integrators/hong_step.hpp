// Hong, Jung, Choi and Welch 2006: a mass-spring system with one volume constraint enforced
// implicitly. Per step of size h (symplectic Euler with the constraint force):
//   Phi_q M^-1 W Phi_q^T lambda = Phi / h^2 + Phi_t / h + Phi_q (v / h + M^-1 F)   (their eq. 14)
//   v' = v + h M^-1 (F - W Phi_q^T lambda),  q' = q + h v',
// one scalar lambda, no linear solve. W are their weight vectors (eq. 15; all ones for global
// deformation); the left side carries W so that the linearised constraint holds exactly (the
// paper leaves W out there and accepts the error). Without a constraint it is the conventional
// mass-spring step. Further rows (supports that hold some components, linear) join the same
// equation as an m x m system, sum_k Phi_q,j M^-1 W_k Phi_q,k^T lambda_k = ..., W_k Hong's
// weights for the volume and ones for the supports, so every row's linearisation holds after the
// step (a linear row exactly).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "isochor/integrators/constrained_system.hpp"
#include "isochor/integrators/integrator.hpp"

namespace isochor {

struct HongOptions {
  double dt = kDefaultFixedStep;
  Eigen::VectorXd weights;  // per dof group (free node); empty: all ones
  long weighted_rows = 1;   // the first rows the weights apply to (the enclosed volume); 1 for the rest
  long max_steps = kDefaultMaxSteps;
};

class FixedStepper;

class HongStep : public SteppingIntegrator {
 public:
  HongStep(ConstrainedSystem& system, HongOptions options);
  ~HongStep() override;
  RunStats run(const std::vector<double>& frame_times, const FrameCallback& on_frame) override;
  void begin(const std::vector<double>& frame_times, const FrameCallback& on_frame) override;
  double step(double t_out) override;
  RunStats finish() override;

 private:
  struct Work;  // a step's weights and scratch
  bool one_step(Work& k, double t, const VectorXd& q, const VectorXd& v, VectorXd& q1, VectorXd& v1, VectorXd& l1,
                std::string& reason);
  ConstrainedSystem& sys_;
  HongOptions opt_;
  RunStats stats_;
  std::unique_ptr<Work> work_;
  std::unique_ptr<FixedStepper> stepper_;
};

}  // namespace isochor
