// The one interface every time integrator and the static solver share: run a system from the
// first frame time to the last, delivering each frame to a callback, and return the run's
// statistics. IDA, KINSOL statics, backward Euler (and its semi-implicit variant) and Hong's step
// run a ConstrainedSystem; XPBD runs a ProjectiveSystem (xpbd.hpp). The choices they share are
// enums, resolved once where the scene is read.
#pragma once
#include <string>
#include <vector>

#include "isochor/run_stats.hpp"

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

}  // namespace isochor
