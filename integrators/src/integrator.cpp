#include "isochor/integrator.hpp"

namespace isochor {

const char* to_string(LinearSolverKind k) {
  switch (k) {
    case LinearSolverKind::klu: return "klu";
    case LinearSolverKind::reduced: return "reduced";
    case LinearSolverKind::krylov: return "krylov";
  }
  return "?";
}

}  // namespace isochor
