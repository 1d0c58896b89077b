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

const char* to_string(KluOrdering k) {
  switch (k) {
    case KluOrdering::metis: return "metis";
    case KluOrdering::colamd: return "colamd";
    case KluOrdering::amd: return "amd";
  }
  return "?";
}

}  // namespace isochor
