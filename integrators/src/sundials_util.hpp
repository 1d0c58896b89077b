// Small helpers around SUNDIALS calls shared by IDA and KINSOL: every return code checked, and a
// matrix-based custom SUNLinearSolver whose setup and solve are the caller's.
#pragma once
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_nvector.h>

#include <functional>
#include <string>

#include "isochor/run_stats.hpp"

namespace isochor {

// A SUNDIALS call that failed at time t: IntegrationError naming the function and its flag.
inline void check(int flag, const char* function, double t = 0.0) {
  if (flag < 0) throw IntegrationError(t, std::string(function) + " failed (flag " + std::to_string(flag) + ")");
}
// A SUNDIALS constructor that returned null.
template <class T>
T* check_ptr(T* p, const char* function) {
  if (!p) throw IntegrationError(0.0, std::string(function) + " returned null (out of memory?)");
  return p;
}

// A serial vector of length n. Made here, where it also calls a function that only SUNDIALS 6's
// serial vector has (N_VEnableFusedOps_Serial): Simbody's libSimTKmath.so exports an old copy of
// N_VNew_Serial and the rest of its API, and a reference to those alone may bind to that copy
// (the sanitizer build did, and crashed in N_VGetArrayPointer); this reference pulls SUNDIALS'
// own object out of the static library, and its definitions then win (NOTES-dependencies §0).
// Its weighted RMS norms (plain and masked, IDA's error and Newton tests) are isochor's own, with
// four partial sums: the same norms up to the order of the additions, faster (sundials_util.cpp).
N_Vector new_serial_vector(sunindextype n, SUNContext ctx);

// Runs f when it goes out of scope: SUNDIALS' objects released on success and on a throw alike.
struct OnExit {
  std::function<void()> f;
  ~OnExit() { f(); }
};

// A direct (matrix-based) custom linear solver: `content` is handed to setup and solve through
// S->content; SUNLinSolFree leaves it alone.
using CustomSetup = int (*)(SUNLinearSolver, SUNMatrix);
using CustomSolve = int (*)(SUNLinearSolver, SUNMatrix, N_Vector, N_Vector, realtype);
SUNLinearSolver make_custom_linear_solver(SUNContext ctx, void* content, CustomSetup setup, CustomSolve solve);

}  // namespace isochor
