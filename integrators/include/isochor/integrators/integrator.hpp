// The one interface every time integrator and the static solver share: run a system from the
// first frame time to the last, delivering each frame to a callback, and return the run's
// statistics. IDA, KINSOL statics, backward Euler (and its semi-implicit variant) and Hong's step
// run a ConstrainedSystem; XPBD runs a ProjectiveSystem (xpbd.hpp). The choices they share are
// enums, resolved once where the scene is read.
#pragma once
#include <string>
#include <vector>

#include "isochor/integrators/run_stats.hpp"

namespace isochor {

// How the Newton systems are solved (docs/scenes.md, integrator.linear_solver):
//   klu      the whole matrix (GGL or KKT) by KLU in a node-grouped METIS order;
//   reduced  the n x n effective stiffness by CHOLMOD, the constraint borders by a Schur complement;
//   krylov   the same reduction with block-Jacobi PCG on the effective stiffness;
//   amg      the same reduction with AMG-preconditioned CG (hypre's BoomerAMG) on it.
enum class LinearSolverKind { klu, reduced, krylov, amg };
// KLU's fill-reducing ordering (klu only).
enum class KluOrdering { metis, colamd, amd };

const char* to_string(LinearSolverKind k);

// Defaults that a scene's [integrator] keys (scene/src/methods/) and the options' members share,
// declared once: integrator.max_steps (steps allowed over the whole run) and integrator.dt (the
// fixed-step methods' step).
constexpr long kDefaultMaxSteps = 10000000;
constexpr double kDefaultFixedStep = 1e-3;
// The solver of the effective stiffness that a reduced kind uses (sparse_factor.hpp).
enum class SymmetricSolverKind;
SymmetricSolverKind symmetric_solver_of(LinearSolverKind k);

class Integrator {
 public:
  virtual ~Integrator() = default;
  // Integrates from frame_times.front() to frame_times.back() (statics: solves at each pseudo-
  // time). Throws IntegrationError after delivering every frame reached.
  virtual RunStats run(const std::vector<double>& frame_times, const FrameCallback& on_frame) = 0;
};

// An integrator that can also be driven a step at a time, for a caller that must act between
// steps (ranks that exchange data, a character's skeleton posed from outside):
//   begin(frame_times, on_frame)  the consistent initial state, the solver set up, frame 0 delivered;
//   step(t_out)                   integrates until the time reached is at least t_out (at most the
//                                 last frame time), delivering every frame passed; returns the time
//                                 reached (steps are the integrator's own: it may pass t_out);
//   finish()                      the run's statistics, the solver released.
// run(frame_times, on_frame) is begin, step to the last frame time, finish. Every integrator is one
// (IDA; backward Euler, semi-implicit, XPBD and Hong's step over fixed_step.hpp's FixedStepper,
// whose steps reach t_out within 1e-9 h; statics, whose time reached is the last frame solved).
class SteppingIntegrator : public Integrator {
 public:
  virtual void begin(const std::vector<double>& frame_times, const FrameCallback& on_frame) = 0;
  virtual double step(double t_out) = 0;
  virtual RunStats finish() = 0;
};

}  // namespace isochor
