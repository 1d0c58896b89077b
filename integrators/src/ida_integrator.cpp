#include "isochor/integrators/ida_integrator.hpp"
#include "ida_newton.hpp"
#include "klu_order.hpp"
#include "sundials_util.hpp"
#include "timing.hpp"
#include "ggl_kkt.hpp"

#include "isochor/integrators/ggl.hpp"
#include "isochor/integrators/initial_state.hpp"
#include "isochor/integrators/interrupt.hpp"
#include "isochor/base/error.hpp"

#include <ida/ida.h>
#include <klu.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace isochor {

struct IdaIntegrator::Impl {
  ConstrainedSystem& sys;
  IdaOptions opt;
  Index n = 0, m = 0;
  GglForm ggl;
  std::unique_ptr<ReducedSolver> reduced;
  std::vector<Index> order;
  RunStats stats;
  // SUNDIALS' objects of the run in progress (begin() to finish()), released in reverse order.
  struct IdaFree {
    void operator()(void* mem) const { IDAFree(&mem); }
  };
  sun::Context context;
  sun::Vector yy, yp, id, atol, yout, ele, ewt;
  sun::Matrix J;
  sun::LinearSolver klu_owner, LS_owner;
  sun::NonlinearSolver nls;
  std::unique_ptr<void, IdaFree> mem;
  SUNContext ctx = nullptr;
  SUNLinearSolver LS = nullptr;   // what IDA calls: the reduced solver, or KLU wrapped to time it
  SUNLinearSolver klu = nullptr;  // klu: SUNDIALS' KLU solver inside LS
  // "klu" above kMultifrontalRows constraints: the GGL system through its KKT matrix
  // (ggl_kkt.hpp) instead of KLU on the GGL matrix.
  bool via_kkt = false;
  std::unique_ptr<GglKktSolver> kkt;
  void* ida_mem = nullptr;
  std::exception_ptr caught;  // thrown inside a callback, rethrown when IDA returns
  long last_newton_failures = 0;
  // The run's course: frame times, the next frame, the time reached, where steps must end.
  std::vector<double> times;
  FrameCallback on_frame;
  std::vector<double> stops;
  std::size_t next_stop = 0, frame = 0;
  double tcur = 0, frame_interval = 1;
  long stalled = 0;
  Clock::time_point wall0;
  bool running = false;
  // ISOCHOR_TRACE_IDA=T (docs/scenes.md): steps and Newton residuals after time T, and at any
  // time why a residual or linear solve failed.
  const char* trace_env = std::getenv("ISOCHOR_TRACE_IDA");
  const bool trace = trace_env != nullptr;
  const double trace_from = trace ? std::atof(trace_env) : std::numeric_limits<double>::infinity();
  // ISOCHOR_CAPTURE_S=T:PATH (docs/scenes.md): the reduced solvers' S at the first setup at or
  // after time T, with the right-hand side of its first solve, written to PATH once.
  std::string capture_path;
  double capture_from = 0;
  void read_capture_env() {
    const char* env = std::getenv("ISOCHOR_CAPTURE_S");
    if (!env) return;
    const std::string v(env);
    const auto colon = v.find(':');
    char* end = nullptr;
    capture_from = std::strtod(v.c_str(), &end);
    if (colon == std::string::npos || colon == 0 || colon + 1 == v.size() || end != v.c_str() + colon)
      throw Error("ISOCHOR_CAPTURE_S: expected TIME:PATH, got \"" + v + "\"");
    if (opt.linear_solver == LinearSolverKind::klu)
      throw Error(
          "ISOCHOR_CAPTURE_S: captures the effective stiffness S of linear_solver = \"reduced\", \"krylov\" or "
          "\"amg\", not \"klu\"");
    capture_path = v.substr(colon + 1);
  }

  Impl(ConstrainedSystem& s, IdaOptions o) : sys(s), opt(std::move(o)), ggl((check_system(s), s)) {
    n = sys.num_dofs();
    m = sys.num_constraints();
    via_kkt = opt.linear_solver == LinearSolverKind::klu && static_cast<std::size_t>(m) > kMultifrontalRows;
    if (opt.linear_solver != LinearSolverKind::klu)
      // CG's residual below what IDA's Newton test can see: 1e-6 rtol, at most 1e-12
      // (docs/decisions.md), unless the scene sets integrator.linear_tol.
      reduced = std::make_unique<ReducedSolver>(ggl, symmetric_solver_of(opt.linear_solver),
                                                opt.linear_tol > 0 ? opt.linear_tol : std::min(1e-12, 1e-6 * opt.rtol));
    else if (opt.ordering == KluOrdering::metis && !via_kkt) {
      check_groups(sys, "KLU's METIS ordering (integrator.ordering = \"metis\")");
      const auto t0 = Clock::now();
      order = metis_order(sys.pattern(), sys.dofs_per_group(), n, 2, sys.constraint_rows(), 2);
      stats.symbolic_seconds += seconds_since(t0);
    }
    read_capture_env();
  }

  int residual(double t, N_Vector yy, N_Vector yp, N_Vector rr) {
    const auto t0 = Clock::now();
    const bool ok = ggl.residual(t, N_VGetArrayPointer(yy), N_VGetArrayPointer(yp), N_VGetArrayPointer(rr));
    stats.assembly_seconds += seconds_since(t0);
    if (!ok && trace) std::fprintf(stderr, "ida t=%.9g: the residual is not finite\n", t);
    if (trace && t >= trace_from) {  // the largest entry of each block: Newton's progress
      const double* r = N_VGetArrayPointer(rr);
      double mx[4] = {0, 0, 0, 0};
      for (Index i = 0; i < 2 * n + 2 * m; ++i) {
        const int b = i < n ? 0 : i < 2 * n ? 1 : i < 2 * n + m ? 2 : 3;
        mx[b] = std::max(mx[b], std::abs(r[i]));
      }
      std::fprintf(stderr, "ida   res t=%.9g |Fq|=%.3g |Fv|=%.3g |Fg|=%.3g |Fgv|=%.3g\n", t, mx[0], mx[1], mx[2],
                   mx[3]);
    }
    return ok ? 0 : 1;  // not finite: recoverable, IDA retries with a smaller step
  }

  // Our Newton iteration's setup after a failed attempt with the old matrix: assemble afresh.
  bool setup_after_failure = false;
  // krylov with jacobian_age: the reduced solver's setup was made from the last assembled
  // Jacobian (reduced_holds_fresh), and this setup only moves it to the new c_j (setup_in_place).
  bool reduced_holds_fresh = false, setup_in_place = false;
  // The last assembled Jacobian (jacobian_age > 0): values, c_j, step count.
  std::vector<double> fresh_vals;
  double fresh_cj = 0;
  long fresh_step = -1;

  int jacobian(double t, double cj, N_Vector yy, N_Vector yp, SUNMatrix J) {
    const auto t0 = Clock::now();
    long nfail = 0, nst = 0;
    check(IDAGetNumNonlinSolvConvFails(ida_mem, &nfail), "IDAGetNumNonlinSolvConvFails", t);
    check(IDAGetNumSteps(ida_mem, &nst), "IDAGetNumSteps", t);
    const bool failed = nfail > last_newton_failures || setup_after_failure;
    last_newton_failures = nfail;
    setup_after_failure = false;
    setup_in_place = false;
    // A Newton failure since the last Jacobian: the pivot order of KLU's first factorisation may
    // have gone stale (c_j changed, contact): ask KLU for a fresh factorisation.
    if (klu && failed && stats.jacobian_evals > 0)
      check(SUNLinSol_KLUReInit(klu, J, SM_NNZ_S(J), SUNKLU_REINIT_PARTIAL), "SUNLinSol_KLUReInit", t);
    const bool reuse = opt.jacobian_age > 0 && !failed && fresh_step >= 0 && nst - fresh_step < opt.jacobian_age;
    if (reuse && reduced_holds_fresh && reduced->can_retarget()) {
      // The reduced solver holds the last assembled Jacobian in its own copies: its setup moves
      // them to the new c_j (reduced_setup), without a copy or a new factor; J is not read.
      setup_in_place = true;
      stats.reused_jacobians++;
      stats.assembly_seconds += seconds_since(t0);
      return 0;
    }
    // SUNMatZero cleared the index arrays too: copy the pattern back, then the values.
    std::memcpy(SM_INDEXPTRS_S(J), ggl.pattern().col_ptr.data(), sizeof(sunindextype) * (ggl.size() + 1));
    std::memcpy(SM_INDEXVALS_S(J), ggl.pattern().row_ind.data(), sizeof(sunindextype) * ggl.pattern().nnz());
    double* vals = SM_DATA_S(J);
    if (reuse) {
      // IDA asks for a setup because c_j changed: the last assembled Jacobian with the new c_j
      // (it enters only the diagonals c_j I and c_j M), as CVODE does with its saved Jacobian.
      std::memcpy(vals, fresh_vals.data(), sizeof(double) * fresh_vals.size());
      ggl.shift_cj(cj - fresh_cj, vals);
      stats.reused_jacobians++;
      stats.assembly_seconds += seconds_since(t0);
      return 0;
    }
    stats.jacobian_evals++;
    ggl.jacobian(t, cj, N_VGetArrayPointer(yy), N_VGetArrayPointer(yp), vals);
    if (opt.jacobian_age > 0) {
      fresh_vals.assign(vals, vals + ggl.pattern().nnz());
      fresh_cj = cj;
      fresh_step = nst;
    }
    stats.assembly_seconds += seconds_since(t0);
    if (opt.on_jacobian) opt.on_jacobian(t, cj, N_VGetArrayPointer(yy), N_VGetArrayPointer(yp), SM_DATA_S(J));
    return 0;
  }
};

namespace {
using Impl = IdaIntegrator::Impl;

int res_fn(sunrealtype t, N_Vector yy, N_Vector yp, N_Vector rr, void* data) {
  auto& s = *static_cast<Impl*>(data);
  return guarded(s.caught, [&] { return s.residual(t, yy, yp, rr); });
}
int jac_fn(sunrealtype t, sunrealtype cj, N_Vector yy, N_Vector yp, N_Vector, SUNMatrix J, void* data, N_Vector,
           N_Vector, N_Vector) {
  auto& s = *static_cast<Impl*>(data);
  return guarded(s.caught, [&] { return s.jacobian(t, cj, yy, yp, J); });
}
// KLU inside a custom linear solver whose content is the integration, to time its setup
// (factorisation) and solve.
int timed_klu_setup(SUNLinearSolver S, SUNMatrix A) {
  auto& s = *static_cast<Impl*>(S->content);
  return guarded(s.caught, [&] {
    if (!SUNLinSol_KLUGetSymbolic(s.klu)) {
      // KLU's symbolic analysis happens inside SUNDIALS' first setup; to report it apart, the same
      // analysis (same ordering and options) is timed once on its own and discarded.
      klu_l_common c = *SUNLinSol_KLUGetCommon(s.klu);
      const auto ta = Clock::now();
      klu_l_symbolic* sym = klu_l_analyze(SM_COLUMNS_S(A), SM_INDEXPTRS_S(A), SM_INDEXVALS_S(A), &c);
      s.stats.symbolic_seconds += seconds_since(ta);
      if (sym) klu_l_free_symbolic(&sym, &c);
    }
    const auto t0 = Clock::now();
    const klu_l_numeric* before = SUNLinSol_KLUGetNumeric(s.klu);
    const int r = SUNLinSolSetup(s.klu, A);
    s.stats.factor_seconds += seconds_since(t0);
    const klu_l_numeric* num = SUNLinSol_KLUGetNumeric(s.klu);
    if (num != before) s.stats.fresh_factorisations++;
    if (num) s.stats.factor_nnz = static_cast<double>(num->lnz + num->unz);
    return r;
  });
}
int timed_klu_solve(SUNLinearSolver S, SUNMatrix A, N_Vector x, N_Vector b, sunrealtype tol) {
  auto& s = *static_cast<Impl*>(S->content);
  return guarded(s.caught, [&] {
    const auto t0 = Clock::now();
    const int r = SUNLinSolSolve(s.klu, A, x, b, tol);
    s.stats.solve_seconds += seconds_since(t0);
    return r;
  });
}
// The GGL system through its KKT matrix (ggl_kkt.hpp): a fresh factorisation at every setup;
// between setups IDA scales the correction for the change of c_j, as it does for KLU.
int kkt_setup(SUNLinearSolver S, SUNMatrix A) {
  auto& s = *static_cast<Impl*>(S->content);
  return guarded(s.caught, [&] {
    const auto t0 = Clock::now();
    double cj = 0;
    check(IDAGetCurrentCj(s.ida_mem, &cj), "IDAGetCurrentCj");
    const bool ok = s.kkt->setup(cj, SM_DATA_S(A));
    s.stats.factor_seconds += seconds_since(t0);
    s.stats.fresh_factorisations++;
    s.stats.factor_nnz = s.kkt->factor_entries();
    if (!ok && s.trace) std::fprintf(stderr, "ida: the KKT matrix of the GGL system is singular\n");
    return ok ? sun::kSuccess : SUNLS_PACKAGE_FAIL_REC;  // singular: IDA retries a smaller step
  });
}
int kkt_solve(SUNLinearSolver S, SUNMatrix, N_Vector x, N_Vector b, sunrealtype) {
  auto& s = *static_cast<Impl*>(S->content);
  return guarded(s.caught, [&] {
    const auto t0 = Clock::now();
    check(IDAGetErrWeights(s.ida_mem, s.ewt.get()), "IDAGetErrWeights");
    const bool ok = s.kkt->solve(N_VGetArrayPointer(b), N_VGetArrayPointer(x), N_VGetArrayPointer(s.ewt.get()));
    s.stats.solve_seconds += seconds_since(t0);
    s.stats.linear_iterations = s.kkt->refinements();
    s.stats.linear_fallbacks = s.kkt->fallbacks();
    if (!ok && s.trace) std::fprintf(stderr, "ida: the refinement of the KKT solve did not converge\n");
    return ok ? sun::kSuccess : SUNLS_PACKAGE_FAIL_REC;
  });
}
// The reduced solver reads the filled GGL matrix.
int reduced_setup_body(Impl& s, SUNMatrix A) {
  const auto t0 = Clock::now();
  double cj = 0;
  check(IDAGetCurrentCj(s.ida_mem, &cj), "IDAGetCurrentCj");
  if (s.setup_in_place) {
    const bool moved = s.reduced->retarget(cj, nullptr);  // A was zeroed by IDA: not read
    s.stats.retargets++;
    s.stats.factor_seconds += seconds_since(t0);
    s.reduced_holds_fresh = moved;
    return moved ? sun::kSuccess : SUNLS_PACKAGE_FAIL_REC;
  }
  const bool ok = s.reduced->setup(cj, SM_DATA_S(A));
  s.reduced_holds_fresh = ok && s.opt.jacobian_age > 0;
  if (!s.capture_path.empty()) {
    sunrealtype t = 0;
    check(IDAGetCurrentTime(s.ida_mem, &t), "IDAGetCurrentTime");
    if (t >= s.capture_from) {
      s.reduced->capture_next(s.capture_path, t);
      s.capture_path.clear();
    }
  }
  s.stats.factor_seconds += seconds_since(t0);
  s.stats.fresh_factorisations++;
  s.stats.factor_nnz = s.reduced->factor_nnz();
  s.stats.symbolic_seconds = s.reduced->analyse_seconds();
  if (!ok && s.trace) std::fprintf(stderr, "ida: the reduced setup failed (c_j = %.3g)\n", cj);
  return ok ? sun::kSuccess : SUNLS_PACKAGE_FAIL_REC;  // not positive definite: retry smaller step
}
int reduced_setup(SUNLinearSolver S, SUNMatrix A) {
  auto& s = *static_cast<Impl*>(S->content);
  return guarded(s.caught, [&] { return reduced_setup_body(s, A); });
}
int reduced_solve_body(Impl& s, N_Vector x, N_Vector b) {
  const auto t0 = Clock::now();
  // Between setups the matrix stays at the setup's c_j and the correction is scaled by
  // 2 / (1 + c_j / c_j,setup), as IDA does for every matrix solver (its own scaling is off for
  // this one: IDASetLinearSolutionScaling). Moving S to the new c_j instead (retarget, cheap on
  // PCG) took 8% fewer Newton iterations on the 16^3 collapse, but Newton then failed less often
  // than with the other solvers, IDA chose other steps, and the error at one tolerance was no
  // longer theirs: the MEBDFDAE pendulum's by up to 0.8 digit (docs/results/tolerance.md).
  double cj = 0;
  check(IDAGetCurrentCj(s.ida_mem, &cj), "IDAGetCurrentCj");
  const double scale = cj != s.reduced->cj() ? 2.0 / (1.0 + cj / s.reduced->cj()) : 1.0;
  const bool ok = s.reduced->solve(N_VGetArrayPointer(b), N_VGetArrayPointer(x));
  if (scale != 1) N_VScale(scale, x, x);
  s.stats.solve_seconds += seconds_since(t0);
  s.stats.linear_iterations = s.reduced->iterations();
  s.stats.linear_fallbacks = s.reduced->fallbacks();
  if (!ok && s.trace) std::fprintf(stderr, "ida: the reduced solve failed\n");
  return ok ? sun::kSuccess : SUNLS_PACKAGE_FAIL_REC;  // PCG did not converge: IDA retries a smaller step
}
int reduced_solve(SUNLinearSolver S, SUNMatrix, N_Vector x, N_Vector b, sunrealtype) {
  auto& s = *static_cast<Impl*>(S->content);
  return guarded(s.caught, [&] { return reduced_solve_body(s, x, b); });
}

// The state vectors (q, v, lambda, mu and their derivatives) from a consistent initial state,
// IDA's id vector (differential q and v, algebraic multipliers) and the absolute tolerances.
void make_vectors(Impl& s, double t0, const VectorXd& q0, const VectorXd& v0, const VectorXd& a0, const VectorXd& l0) {
  const Index n = s.n, m = s.m, N = 2 * n + 2 * m;
  s.yy = new_serial_vector(N, s.ctx);
  s.yp = new_serial_vector(N, s.ctx);
  s.id = new_serial_vector(N, s.ctx);
  s.atol = new_serial_vector(N, s.ctx);
  double* y = N_VGetArrayPointer(s.yy.get());
  double* d = N_VGetArrayPointer(s.yp.get());
  Eigen::Map<VectorXd>(y, N).setZero();
  Eigen::Map<VectorXd>(d, N).setZero();
  Eigen::Map<VectorXd>(y, n) = q0;
  Eigen::Map<VectorXd>(y + n, n) = v0;
  if (m) Eigen::Map<VectorXd>(y + 2 * n, m) = l0;
  Eigen::Map<VectorXd>(d, n) = v0;
  Eigen::Map<VectorXd>(d + n, n) = a0;
  double* idv = N_VGetArrayPointer(s.id.get());
  double* av = N_VGetArrayPointer(s.atol.get());
  const double atol_v = s.opt.atol_v > 0 ? s.opt.atol_v : 100.0 * s.opt.atol_q;
  const double atol_l = s.opt.atol_lambda > 0 ? s.opt.atol_lambda : 1e-6 * s.sys.force_scale();
  for (Index i = 0; i < N; ++i) {
    idv[i] = i < 2 * n ? 1.0 : 0.0;
    av[i] = i < n ? s.opt.atol_q : i < 2 * n ? atol_v : atol_l;
  }
  if (!m) return;
  // mu multiplies G^T in the velocity equation: its natural scale is atol_v / |G_j|.
  std::vector<std::vector<double>> G(m);
  for (Index j = 0; j < m; ++j) G[j].resize(s.sys.constraint_rows()[j].size());
  s.sys.constraint_jacobian(t0, q0, G, nullptr);
  for (Index j = 0; j < m; ++j) {
    double nrm = 0;
    for (double x : G[j]) nrm += x * x;
    av[2 * n + m + j] = atol_v / std::max(1e-300, std::sqrt(nrm));
    av[2 * n + j] = atol_l / std::max(1e-300, std::sqrt(nrm));
  }
}

// A position-based first step: the error 1/2 a h^2 of a first step equals the position tolerance,
// h0 = sqrt(2 / |a|_wrms) (IDA's own, 0.5 / |y'|, is too small for Newton on the GGL matrix at
// tight tolerances: docs/decisions.md). 0 when the acceleration is zero.
double first_step(const Impl& s, const VectorXd& q0, const VectorXd& a0, double span) {
  double sum = 0;
  for (Index i = 0; i < s.n; ++i) {
    const double w = a0[i] / (s.opt.rtol * std::abs(q0[i]) + s.opt.atol_q);
    sum += w * w;
  }
  const double anorm = std::sqrt(sum / static_cast<double>(std::max<Index>(s.n, 1)));
  if (anorm <= 0) return 0;
  double h0 = std::min(std::sqrt(2.0 / anorm), 1e-3 * span);
  if (s.opt.max_step > 0) h0 = std::min(h0, s.opt.max_step);
  return h0;
}

// IDA's memory with the run's options: tolerances, the algebraic components, our Newton iteration
// where the reduced solver keeps its matrix, orders, step limits and the first step.
void create_ida(Impl& s, double t0, double t_end, const VectorXd& q0, const VectorXd& a0) {
  s.mem.reset(check_ptr(IDACreate(s.ctx), "IDACreate"));
  void* mem = s.ida_mem = s.mem.get();
  check(IDAInit(mem, res_fn, t0, s.yy.get(), s.yp.get()), "IDAInit", t0);
  check(IDASVtolerances(mem, s.opt.rtol, s.atol.get()), "IDASVtolerances", t0);
  check(IDASetUserData(mem, &s), "IDASetUserData", t0);
  check(IDASetId(mem, s.id.get()), "IDASetId", t0);
  check(IDASetSuppressAlg(mem, SUNTRUE), "IDASetSuppressAlg", t0);
  if (s.reduced && s.reduced->can_retarget()) {
    // The reduced solver can keep its matrix across setups (jacobian_age): IDA's iteration, told
    // when a setup kept it (ida_newton.hpp). Set before the iteration limit, which it resets.
    IdaNewtonHooks hooks;
    hooks.before_setup = [&s](bool after_failure) { s.setup_after_failure = after_failure; };
    hooks.kept_matrix = [&s]() { return s.setup_in_place; };
    s.nls.reset(check_ptr(make_ida_newton(s.yy.get(), s.ctx, std::move(hooks)), "make_ida_newton"));
    check(IDASetNonlinearSolver(mem, s.nls.get()), "IDASetNonlinearSolver", t0);
  }
  const double newton_coef = s.opt.newton_coef > 0 ? s.opt.newton_coef : IdaOptions::kDefaultNewtonCoef;
  check(IDASetNonlinConvCoef(mem, newton_coef), "IDASetNonlinConvCoef", t0);
  check(IDASetMaxOrd(mem, s.opt.max_order), "IDASetMaxOrd", t0);
  check(IDASetMaxNonlinIters(mem, s.opt.max_newton), "IDASetMaxNonlinIters", t0);
  if (s.opt.max_step > 0) check(IDASetMaxStep(mem, s.opt.max_step), "IDASetMaxStep", t0);
  const double h0 = s.opt.initial_step > 0        ? s.opt.initial_step
                    : a0.size() > 0 && t_end > t0 ? first_step(s, q0, a0, t_end - t0)
                                                  : 0.0;
  if (h0 > 0) check(IDASetInitStep(mem, h0), "IDASetInitStep", t0);
  check(IDASetStopTime(mem, t_end), "IDASetStopTime", t0);
  check(IDASetMaxNumSteps(mem, 100000), "IDASetMaxNumSteps", t0);
}

// The Jacobian matrix and the linear solver: the reduced solver, the KKT solver, or KLU (in
// METIS's node-grouped order or its own) inside a wrapper that times it.
void attach_linear_solver(Impl& s, double t0) {
  const Index N = 2 * s.n + 2 * s.m;
  s.J.reset(check_ptr(SUNSparseMatrix(N, N, s.ggl.pattern().nnz(), CSC_MAT, s.ctx), "SUNSparseMatrix"));
  if (s.reduced) {
    s.LS_owner = make_custom_linear_solver(s.ctx, &s, reduced_setup, reduced_solve);
  } else if (s.via_kkt) {
    const auto ta = Clock::now();
    s.kkt = std::make_unique<GglKktSolver>(s.ggl);
    s.stats.symbolic_seconds += seconds_since(ta);
    s.LS_owner = make_custom_linear_solver(s.ctx, &s, kkt_setup, kkt_solve);
  } else {
    s.klu_owner.reset(check_ptr(SUNLinSol_KLU(s.yy.get(), s.J.get(), s.ctx), "SUNLinSol_KLU"));
    s.klu = s.klu_owner.get();
    if (s.opt.ordering == KluOrdering::metis)
      use_klu_order(s.klu, &s.order);
    else
      check(SUNLinSol_KLUSetOrdering(s.klu, s.opt.ordering == KluOrdering::amd ? 0 : 1), "SUNLinSol_KLUSetOrdering",
            t0);
    check(SUNLinSolInitialize(s.klu), "SUNLinSolInitialize", t0);
    s.LS_owner = make_custom_linear_solver(s.ctx, &s, timed_klu_setup, timed_klu_solve);
  }
  s.LS = s.LS_owner.get();
  check(IDASetLinearSolver(s.ida_mem, s.LS, s.J.get()), "IDASetLinearSolver", t0);
  if (s.reduced) check(IDASetLinearSolutionScaling(s.ida_mem, SUNFALSE), "IDASetLinearSolutionScaling", t0);
  check(IDASetJacFn(s.ida_mem, jac_fn), "IDASetJacFn", t0);
}

// The statistics at time t, with a sample for the frame.
void collect(Impl& s, double t) {
  void* mem = s.ida_mem;
  check(IDAGetNumSteps(mem, &s.stats.steps), "IDAGetNumSteps", t);
  check(IDAGetNumResEvals(mem, &s.stats.residual_evals), "IDAGetNumResEvals", t);
  check(IDAGetNumLinSolvSetups(mem, &s.stats.linear_setups), "IDAGetNumLinSolvSetups", t);
  check(IDAGetNumNonlinSolvIters(mem, &s.stats.newton_iterations), "IDAGetNumNonlinSolvIters", t);
  check(IDAGetNumNonlinSolvConvFails(mem, &s.stats.newton_failures), "IDAGetNumNonlinSolvConvFails", t);
  check(IDAGetNumErrTestFails(mem, &s.stats.error_test_failures), "IDAGetNumErrTestFails", t);
  int order = 0;
  double h = 0;
  check(IDAGetLastOrder(mem, &order), "IDAGetLastOrder", t);
  check(IDAGetLastStep(mem, &h), "IDAGetLastStep", t);
  s.stats.frames.push_back({s.stats.steps, s.stats.newton_iterations, s.stats.error_test_failures,
                            s.stats.newton_failures, s.stats.jacobian_evals, order, h});
}

// ISOCHOR_TRACE_IDA=T: one line per step ending after time T, on stderr: the step, order,
// failures so far, the share of the weighted local error estimate held by positions and by
// velocities (the multipliers are out of the error test), and the three dofs (free node.axis,
// block) that weigh most.
void trace_step(Impl& s, double t) {
  void* mem = s.ida_mem;
  const Index n = s.n, N = 2 * s.n + 2 * s.m;
  long nst = 0, netf = 0, ncfn = 0, nni = 0;
  int order = 0;
  double h = 0;
  check(IDAGetNumSteps(mem, &nst), "IDAGetNumSteps", t);
  check(IDAGetNumErrTestFails(mem, &netf), "IDAGetNumErrTestFails", t);
  check(IDAGetNumNonlinSolvConvFails(mem, &ncfn), "IDAGetNumNonlinSolvConvFails", t);
  check(IDAGetNumNonlinSolvIters(mem, &nni), "IDAGetNumNonlinSolvIters", t);
  check(IDAGetLastOrder(mem, &order), "IDAGetLastOrder", t);
  check(IDAGetLastStep(mem, &h), "IDAGetLastStep", t);
  check(IDAGetEstLocalErrors(mem, s.ele.get()), "IDAGetEstLocalErrors", t);
  check(IDAGetErrWeights(mem, s.ewt.get()), "IDAGetErrWeights", t);
  const double* e = N_VGetArrayPointer(s.ele.get());
  const double* w = N_VGetArrayPointer(s.ewt.get());
  double share[2] = {0, 0}, total = 0;
  std::vector<std::pair<double, Index>> top;
  for (Index i = 0; i < 2 * n; ++i) {
    const double x = (e[i] * w[i]) * (e[i] * w[i]);
    share[i < n ? 0 : 1] += x;
    total += x;
    top.emplace_back(x, i);
  }
  const std::size_t k3 = std::min<std::size_t>(3, top.size());
  std::partial_sort(top.begin(), top.begin() + static_cast<std::ptrdiff_t>(k3), top.end(),
                    [](const auto& a, const auto& b) { return a.first > b.first; });
  std::fprintf(stderr, "ida t=%.9g h=%.3g k=%d steps=%ld netf=%ld ncfn=%ld nni=%ld err=%.3g q=%.2f v=%.2f top:", t, h,
               order, nst, netf, ncfn, nni, std::sqrt(total / static_cast<double>(N)),
               share[0] / std::max(total, 1e-300), share[1] / std::max(total, 1e-300));
  for (std::size_t j = 0; j < k3; ++j) {
    const Index i = top[j].second % n;
    std::fprintf(stderr, " %ld.%ld%s(%.2f)", static_cast<long>(i / 3), static_cast<long>(i % 3),
                 top[j].second < n ? "q" : "v", top[j].first / std::max(total, 1e-300));
  }
  std::fprintf(stderr, "\n");
}

// Steps end only where the scene is not smooth (its breakpoints), at the last frame and, with
// stop_at_frames, at every frame; frames in between come from IDA's interpolant.
std::vector<double> step_stops(Impl& s, double t0) {
  const std::vector<double>& times = s.times;
  std::vector<double> stops{times.back()};
  for (double tb : s.sys.breakpoints())
    if (tb > t0 && tb < times.back()) stops.push_back(tb);
  if (s.opt.stop_at_frames) stops.insert(stops.end(), times.begin(), times.end());
  std::sort(stops.begin(), stops.end());
  stops.erase(std::unique(stops.begin(), stops.end()), stops.end());
  return stops;
}

// Delivers every frame at or before the time reached: a step that ended on the frame is taken as
// it is, the others are interpolated; either way the frame is projected back onto g = 0 and
// G v + dg/dt = 0 (the interpolant holds the constraints to the integration error only).
void deliver_frames(Impl& s) {
  const Index n = s.n, m = s.m;
  VectorXd qf(n), vf(n), lf(m);
  while (s.frame < s.times.size() && s.times[s.frame] <= s.tcur) {
    const double tf = s.times[s.frame];
    if (tf == s.tcur)
      N_VScale(1.0, s.yy.get(), s.yout.get());
    else if (IDAGetDky(s.ida_mem, tf, 0, s.yout.get()) < 0)
      throw IntegrationError(tf, "IDAGetDky could not interpolate the frame");
    const double* yo = N_VGetArrayPointer(s.yout.get());
    qf = Eigen::Map<const VectorXd>(yo, n);
    vf = Eigen::Map<const VectorXd>(yo + n, n);
    lf = Eigen::Map<const VectorXd>(yo + 2 * n, m);
    const auto tp = Clock::now();
    project_state(s.sys, tf, qf, vf);
    s.stats.projection_seconds += seconds_since(tp);
    collect(s, tf);
    s.on_frame(static_cast<int>(s.frame), tf, qf, vf, lf, s.stats.frames.back());
    ++s.frame;
  }
}

// After a step: the step limit and progress. No progress means steps below kStall of the frame
// interval, kStallSteps of them in a row (a million steps per frame or more; the ball's impact,
// the stiffest event in the demos, steps at 5e-3 of it). Such a run would take days, so it stops
// and says why.
void check_progress(Impl& s) {
  constexpr double kStall = 1e-7;
  constexpr long kStallSteps = 1000;
  long steps = 0;
  check(IDAGetNumSteps(s.ida_mem, &steps), "IDAGetNumSteps", s.tcur);
  if (steps > s.opt.max_steps)
    throw IntegrationError(s.tcur, "more than " + std::to_string(s.opt.max_steps) + " steps (integrator.max_steps)");
  double h = 0;
  check(IDAGetLastStep(s.ida_mem, &h), "IDAGetLastStep", s.tcur);
  s.stalled = std::abs(h) < kStall * s.frame_interval ? s.stalled + 1 : 0;
  if (s.stalled >= kStallSteps) {
    char buf[240];
    std::snprintf(
        buf, sizeof buf,
        "no progress: %ld steps in a row below %g of the frame interval (the last step %.3g s; the model or its "
        "state is too stiff to integrate, e.g. a body starting inside a contact or an inverted mesh)",
        kStallSteps, kStall, h);
    throw IntegrationError(s.tcur, buf);
  }
}

// One IDA step towards `target`, ending at the next stop at the latest.
void one_step(Impl& s, double target) {
  step_boundary(s.tcur);
  while (s.next_stop < s.stops.size() && s.stops[s.next_stop] <= s.tcur) ++s.next_stop;
  check(IDASetStopTime(s.ida_mem, s.stops[std::min(s.next_stop, s.stops.size() - 1)]), "IDASetStopTime", s.tcur);
  double tret = s.tcur;
  const int flag = IDASolve(s.ida_mem, target, &tret, s.yy.get(), s.yp.get(), IDA_ONE_STEP);
  rethrow_caught(s.caught);
  if (flag < 0) {
    char* name = IDAGetReturnFlagName(flag);
    std::string reason = name ? name : "unknown IDA failure";
    free(name);
    throw IntegrationError(tret, reason);
  }
  s.tcur = tret;
  if (s.tcur >= s.trace_from) trace_step(s, s.tcur);
  check_progress(s);
}

// Releases SUNDIALS' objects of the run (IDA's memory first, the context last).
void release(Impl& s) {
  s.mem.reset();
  s.nls.reset();
  s.LS_owner.reset();
  s.klu_owner.reset();
  s.kkt.reset();
  s.J.reset();
  for (sun::Vector* v : {&s.yy, &s.yp, &s.id, &s.atol, &s.yout, &s.ele, &s.ewt}) v->reset();
  s.context.reset();
  s.ctx = nullptr;
  s.LS = s.klu = nullptr;
  s.ida_mem = nullptr;
  s.running = false;
}

}  // namespace

IdaIntegrator::IdaIntegrator(ConstrainedSystem& system, IdaOptions options)
    : impl_(std::make_unique<Impl>(system, std::move(options))) {}
IdaIntegrator::~IdaIntegrator() = default;

void IdaIntegrator::begin(const std::vector<double>& times, const FrameCallback& on_frame) {
  Impl& s = *impl_;
  if (times.empty()) throw Error("IDA: no frame times to integrate to");
  release(s);
  s.wall0 = Clock::now();
  s.times = times;
  s.on_frame = on_frame;
  const double t0 = times.front();
  VectorXd q0, v0, a0, l0;
  consistent_initial_state(s.sys, t0, q0, v0, a0, l0);
  if (!s.reduced && constraints_dependent(s.sys, t0, q0))
    throw IntegrationError(
        t0,
        "the constraints are linearly dependent (e.g. zones.global together with zones that partition the "
        "mesh), which makes the matrix that KLU factors singular: remove the redundant zones, or set "
        "integrator.linear_solver = \"reduced\" or \"krylov\", which take the multipliers of smallest norm");
  s.running = true;
  s.context = sun::make_context(t0);
  s.ctx = s.context.get();
  make_vectors(s, t0, q0, v0, a0, l0);
  create_ida(s, t0, times.back(), q0, a0);
  attach_linear_solver(s, t0);
  s.stops = step_stops(s, t0);
  s.next_stop = 0;
  if (s.trace) s.ele.reset(check_ptr(N_VClone(s.yy.get()), "N_VClone"));
  if (s.trace || s.kkt) s.ewt.reset(check_ptr(N_VClone(s.yy.get()), "N_VClone"));
  s.yout.reset(check_ptr(N_VClone(s.yy.get()), "N_VClone"));
  s.frame_interval = times.size() > 1 ? times[1] - times[0] : std::max(times.back() - t0, 1.0);
  s.stalled = 0;
  s.frame = 0;
  s.tcur = t0;
  deliver_frames(s);
}

double IdaIntegrator::step(double t_out) {
  Impl& s = *impl_;
  if (!s.running) throw Error("IDA: step() before begin()");
  const double target = std::min(t_out, s.times.back());
  while (s.tcur < target) {
    one_step(s, s.frame < s.times.size() ? s.times[s.frame] : s.times.back());
    deliver_frames(s);
  }
  return s.tcur;
}

RunStats IdaIntegrator::finish() {
  Impl& s = *impl_;
  s.stats.wall_seconds = seconds_since(s.wall0);
  release(s);
  return s.stats;
}

RunStats IdaIntegrator::run(const std::vector<double>& times, const FrameCallback& on_frame) {
  try {
    begin(times, on_frame);
    step(times.back());
  } catch (...) {
    release(*impl_);
    throw;
  }
  return finish();
}

}  // namespace isochor
