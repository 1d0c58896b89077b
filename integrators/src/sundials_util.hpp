// Small helpers around SUNDIALS calls shared by IDA and KINSOL: every return code checked, owners
// that release SUNDIALS' objects (unique_ptr with their destroy functions), callbacks that keep an
// exception for the caller instead of unwinding through SUNDIALS' C frames, and a matrix-based
// custom SUNLinearSolver whose setup and solve are the caller's.
#pragma once
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_nvector.h>

#include <sunmatrix/sunmatrix_sparse.h>

#include <exception>
#include <memory>
#include <string>
#include <type_traits>

#include "isochor/integrators/run_stats.hpp"
#include "sundials_compat.hpp"

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

// Owners of SUNDIALS' objects, each released by its destroy function. Declared in the order
// they are made (context, vectors, matrix, solvers, solver memory), they are released in reverse.
namespace sun {
template <class Handle, void (*Free)(Handle)>
struct Release {
  void operator()(Handle h) const {
    if (h) Free(h);
  }
};
inline void free_context(SUNContext c) { SUNContext_Free(&c); }
inline void free_nonlinear_solver(SUNNonlinearSolver s) { SUNNonlinSolFree(s); }
inline void free_linear_solver(SUNLinearSolver s) { SUNLinSolFree(s); }
using Context = std::unique_ptr<std::remove_pointer_t<SUNContext>, Release<SUNContext, free_context>>;
using Vector = std::unique_ptr<std::remove_pointer_t<N_Vector>, Release<N_Vector, N_VDestroy>>;
using Matrix = std::unique_ptr<std::remove_pointer_t<SUNMatrix>, Release<SUNMatrix, SUNMatDestroy>>;
using LinearSolver =
    std::unique_ptr<std::remove_pointer_t<SUNLinearSolver>, Release<SUNLinearSolver, free_linear_solver>>;
using NonlinearSolver =
    std::unique_ptr<std::remove_pointer_t<SUNNonlinearSolver>, Release<SUNNonlinearSolver, free_nonlinear_solver>>;
// A new context (IntegrationError if SUNDIALS cannot make one). quiet: SUNDIALS 7 prints no error
// messages for solvers on it (SUNDIALS 6 silences per solver: KINSetErrHandlerFn).
Context make_context(double t, bool quiet = false);
}  // namespace sun

// A serial vector of length n. Made here, where it also calls a function that only SUNDIALS 6's
// serial vector has (N_VEnableFusedOps_Serial): Simbody's libSimTKmath.so exports an old copy of
// N_VNew_Serial and the rest of its API, and a reference to those alone may bind to that copy
// (the sanitizer build did, and crashed in N_VGetArrayPointer); this reference pulls SUNDIALS'
// own object out of the static library, and its definitions then win (NOTES-dependencies §0).
// Its weighted RMS norms (plain and masked, IDA's error and Newton tests) are isochor's own, with
// four partial sums: the same norms up to the order of the additions, faster (sundials_util.cpp).
sun::Vector new_serial_vector(sunindextype n, SUNContext ctx);

// Runs a SUNDIALS callback's body: an exception it throws is kept in `caught` (the first one) and
// the callback returns -1, an unrecoverable failure, so that SUNDIALS unwinds by its own return
// codes; the caller rethrows it (rethrow_caught) when the solver returns.
template <class F>
int guarded(std::exception_ptr& caught, F&& body) noexcept {
  try {
    return body();
  } catch (...) {
    if (!caught) caught = std::current_exception();
    return -1;
  }
}
// Rethrows what a guarded callback kept, if anything.
inline void rethrow_caught(std::exception_ptr& caught) {
  if (caught) {
    std::exception_ptr e = caught;
    caught = nullptr;
    std::rethrow_exception(e);
  }
}

// A direct (matrix-based) custom linear solver: `content` is handed to setup and solve through
// S->content; SUNLinSolFree leaves it alone.
using CustomSetup = int (*)(SUNLinearSolver, SUNMatrix);
using CustomSolve = int (*)(SUNLinearSolver, SUNMatrix, N_Vector, N_Vector, sunrealtype);
sun::LinearSolver make_custom_linear_solver(SUNContext ctx, void* content, CustomSetup setup, CustomSolve solve);

}  // namespace isochor
