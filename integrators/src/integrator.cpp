#include "isochor/integrators/integrator.hpp"

#include "isochor/integrators/sparse_factor.hpp"

namespace isochor {

const char* to_string(LinearSolverKind k) {
  switch (k) {
    case LinearSolverKind::klu:
      return "klu";
    case LinearSolverKind::reduced:
      return "reduced";
    case LinearSolverKind::krylov:
      return "krylov";
    case LinearSolverKind::amg:
      return "amg";
  }
  return "?";
}

SymmetricSolverKind symmetric_solver_of(LinearSolverKind k) {
  return k == LinearSolverKind::krylov ? SymmetricSolverKind::pcg
         : k == LinearSolverKind::amg  ? SymmetricSolverKind::amg
                                       : SymmetricSolverKind::cholmod;
}

}  // namespace isochor
