// IDA's Newton iteration for matrices kept across setups (ida_newton.hpp).
#include "ida_newton.hpp"
#include "sundials_compat.hpp"

#include <ida/ida.h>

#include <cmath>
#include <new>
#include <utility>

namespace isochor {

namespace {

struct Newton {
  SUNNonlinSolSysFn sys = nullptr;
  SUNNonlinSolLSetupFn lsetup = nullptr;
  SUNNonlinSolLSolveFn lsolve = nullptr;
  N_Vector delta = nullptr;
  int max_iters = 4, cur_iter = 0;
  long iters = 0, conv_fails = 0;  // of the last solve (IDA adds them up)
  bool jcur = false;               // the linear solver's matrix was set up in this step
  double ss = 20, first_norm = 0;  // the predicted error factor, the first correction's norm
  double last_cj = 0;              // IDA's c_j at the last solve
  IdaNewtonHooks hooks;
};

Newton& content(SUNNonlinearSolver s) { return *static_cast<Newton*>(s->content); }

// The test on correction `m` (0-based) of norm `norm`: converged, or go on, or diverging.
int test(Newton& c, double norm, double tol) {
  if (c.cur_iter == 0) {
    c.first_norm = norm;
    if (norm <= 1e-4 * tol) return sun::kSuccess;
  } else {
    const double rate = std::pow(norm / c.first_norm, 1.0 / c.cur_iter);
    if (rate > 0.9) return SUN_NLS_CONV_RECVR;
    c.ss = rate / (1.0 - rate);
  }
  return c.ss * norm <= tol ? sun::kSuccess : SUN_NLS_CONTINUE;
}

int solve(SUNNonlinearSolver s, N_Vector, N_Vector ycor, N_Vector w, sunrealtype tol, sunbooleantype call_setup,
          void* mem) {
  Newton& c = content(s);
  c.iters = 0;
  c.conv_fails = 0;
  double cj = 0;
  if (IDAGetCurrentCj(mem, &cj) < 0) return sun::kNonlinearMemNull;
  // As IDA: a new c_j forgets the rate (the matrix, or its shift to c_j, is not the one measured).
  if (cj != c.last_cj) c.ss = 100;
  c.last_cj = cj;
  bool jbad = false;
  int r = sun::kSuccess;
  for (;;) {  // an attempt: residual, setup if asked, the corrections
    r = c.sys(ycor, c.delta, mem);
    if (r != sun::kSuccess) break;
    if (call_setup) {
      sunbooleantype jc = SUNFALSE;
      c.hooks.before_setup(jbad);
      r = c.lsetup(jbad, &jc, mem);
      // A kept matrix is not current: a failure with it earns a fresh one.
      const bool kept = c.hooks.kept_matrix();
      c.jcur = jc && !kept;
      if (!kept) c.ss = 20;
      if (r != sun::kSuccess) break;
    }
    for (c.cur_iter = 0;;) {
      c.iters++;
      N_VScale(-1.0, c.delta, c.delta);
      r = c.lsolve(c.delta, mem);
      if (r != sun::kSuccess) break;
      N_VLinearSum(1.0, ycor, 1.0, c.delta, ycor);
      r = test(c, N_VWrmsNorm(c.delta, w), tol);
      if (r == sun::kSuccess) {
        c.jcur = false;
        return sun::kSuccess;
      }
      if (r != SUN_NLS_CONTINUE) break;
      if (++c.cur_iter >= c.max_iters) {
        r = SUN_NLS_CONV_RECVR;
        break;
      }
      r = c.sys(ycor, c.delta, mem);
      if (r != sun::kSuccess) break;
    }
    // A recoverable failure with a matrix from an earlier step: once more with a fresh setup.
    if (r > 0 && !c.jcur && c.lsetup) {
      c.conv_fails++;
      call_setup = SUNTRUE;
      jbad = true;
      N_VConst(0.0, ycor);
      continue;
    }
    break;
  }
  c.conv_fails++;
  return r;
}

SUNNonlinearSolver_Type get_type(SUNNonlinearSolver) { return SUNNONLINEARSOLVER_ROOTFIND; }
int initialize(SUNNonlinearSolver s) {
  Newton& c = content(s);
  c.iters = c.conv_fails = 0;
  c.jcur = false;
  return c.sys && c.lsolve ? sun::kSuccess : sun::kNonlinearMemNull;
}
int free_solver(SUNNonlinearSolver s) {
  if (!s) return sun::kSuccess;
  if (s->content) {
    if (content(s).delta) N_VDestroy(content(s).delta);
    delete &content(s);
    s->content = nullptr;
  }
  SUNNonlinSolFreeEmpty(s);
  return sun::kSuccess;
}
int set_sys(SUNNonlinearSolver s, SUNNonlinSolSysFn f) {
  content(s).sys = f;
  return f ? sun::kSuccess : sun::kNonlinearIllInput;
}
int set_lsetup(SUNNonlinearSolver s, SUNNonlinSolLSetupFn f) {
  content(s).lsetup = f;
  return sun::kSuccess;
}
int set_lsolve(SUNNonlinearSolver s, SUNNonlinSolLSolveFn f) {
  content(s).lsolve = f;
  return f ? sun::kSuccess : sun::kNonlinearIllInput;
}
// IDA hands its own test (and its memory); this solver uses its own (above) instead.
int set_ctest(SUNNonlinearSolver, SUNNonlinSolConvTestFn f, void*) {
  return f ? sun::kSuccess : sun::kNonlinearIllInput;
}
int set_max_iters(SUNNonlinearSolver s, int n) {
  if (n < 1) return sun::kNonlinearIllInput;
  content(s).max_iters = n;
  return sun::kSuccess;
}
int get_iters(SUNNonlinearSolver s, long* n) {
  *n = content(s).iters;
  return sun::kSuccess;
}
int get_cur_iter(SUNNonlinearSolver s, int* n) {
  *n = content(s).cur_iter;
  return sun::kSuccess;
}
int get_conv_fails(SUNNonlinearSolver s, long* n) {
  *n = content(s).conv_fails;
  return sun::kSuccess;
}

}  // namespace

SUNNonlinearSolver make_ida_newton(N_Vector y, SUNContext ctx, IdaNewtonHooks hooks) {
  SUNNonlinearSolver s = SUNNonlinSolNewEmpty(ctx);
  if (!s) return nullptr;
  auto* c = new (std::nothrow) Newton;
  if (!c) {
    SUNNonlinSolFreeEmpty(s);
    return nullptr;
  }
  s->content = c;
  c->hooks = std::move(hooks);
  c->delta = N_VClone(y);
  s->ops->gettype = get_type;
  s->ops->initialize = initialize;
  s->ops->solve = solve;
  s->ops->free = free_solver;
  s->ops->setsysfn = set_sys;
  s->ops->setlsetupfn = set_lsetup;
  s->ops->setlsolvefn = set_lsolve;
  s->ops->setctestfn = set_ctest;
  s->ops->setmaxiters = set_max_iters;
  s->ops->getnumiters = get_iters;
  s->ops->getcuriter = get_cur_iter;
  s->ops->getnumconvfails = get_conv_fails;
  if (!c->delta) {
    free_solver(s);
    return nullptr;
  }
  return s;
}

}  // namespace isochor
