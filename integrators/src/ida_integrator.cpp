#include "isochor/ida_integrator.hpp"
#include "klu_order.hpp"
#include "timing.hpp"

#include "isochor/ggl.hpp"

#include <ida/ida.h>
#include <klu.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace isochor {

namespace {

}  // namespace

struct IdaIntegrator::Impl {
  ConstrainedSystem& sys;
  IdaOptions opt;
  Index n = 0, m = 0;
  GglForm ggl;
  std::unique_ptr<ReducedSolver> reduced;
  std::vector<Index> order;
  IdaStats stats;
  SUNContext ctx = nullptr;
  SUNLinearSolver LS = nullptr;
  long last_newton_failures = 0;
  // KLU's own setup and solve, wrapped to time them.
  int (*klu_setup)(SUNLinearSolver, SUNMatrix) = nullptr;
  int (*klu_solve)(SUNLinearSolver, SUNMatrix, N_Vector, N_Vector, realtype) = nullptr;
  void* ida_mem = nullptr;

  Impl(ConstrainedSystem& s, IdaOptions o) : sys(s), opt(std::move(o)), ggl(s) {
    n = sys.num_dofs();
    m = sys.num_constraints();
    if (opt.linear_solver == "reduced" || opt.linear_solver == "krylov")
      // CG's residual must sit below what IDA's Newton test can see: 1e-12 serves rtol >= 1e-6;
      // at rtol 1e-8, atol 1e-11 it did not (a 600-tet ball, undamped: IDA_CONV_FAIL at 92 ms),
      // 1e-14 did. So 1e-6 rtol, at most 1e-12.
      reduced = std::make_unique<ReducedSolver>(ggl, opt.linear_solver == "krylov" ? "pcg" : "cholmod",
                                                std::min(1e-12, 1e-6 * opt.rtol));
    else if (opt.ordering == "metis") {
      const auto t0 = Clock::now();
      order = metis_order(sys.pattern(), sys.dofs_per_group(), n, 2, sys.constraint_rows(), 2);
      stats.symbolic_seconds += seconds_since(t0);
    }
  }

  int residual(double t, N_Vector yy, N_Vector yp, N_Vector rr) {
    const auto t0 = Clock::now();
    const bool ok = ggl.residual(t, N_VGetArrayPointer(yy), N_VGetArrayPointer(yp), N_VGetArrayPointer(rr));
    stats.assembly_seconds += seconds_since(t0);
    return ok ? 0 : 1;  // not finite: recoverable, IDA retries with a smaller step
  }

  // The last assembled Jacobian (jacobian_age > 0): values, c_j, step count.
  std::vector<double> fresh_vals;
  double fresh_cj = 0;
  long fresh_step = -1;

  int jacobian(double t, double cj, N_Vector yy, N_Vector yp, SUNMatrix J) {
    const auto t0 = Clock::now();
    long nfail = 0, nst = 0;
    IDAGetNumNonlinSolvConvFails(ida_mem, &nfail);
    IDAGetNumSteps(ida_mem, &nst);
    const bool failed = nfail > last_newton_failures;
    last_newton_failures = nfail;
    // A Newton failure since the last Jacobian: the pivot order of KLU's first factorisation may
    // have gone stale (c_j changed, contact): ask KLU for a fresh factorisation.
    if (!reduced && failed && stats.jacobian_evals > 0) SUNLinSol_KLUReInit(LS, J, SM_NNZ_S(J), SUNKLU_REINIT_PARTIAL);
    // SUNMatZero cleared the index arrays too: copy the pattern back, then the values.
    std::memcpy(SM_INDEXPTRS_S(J), ggl.pattern().col_ptr.data(), sizeof(sunindextype) * (ggl.size() + 1));
    std::memcpy(SM_INDEXVALS_S(J), ggl.pattern().row_ind.data(), sizeof(sunindextype) * ggl.pattern().nnz());
    double* vals = SM_DATA_S(J);
    if (opt.jacobian_age > 0 && !failed && fresh_step >= 0 && nst - fresh_step < opt.jacobian_age) {
      // IDA asks for a setup because c_j changed: the last assembled Jacobian with the new c_j
      // (it enters only the diagonals c_j I and c_j M), as CVODE does with its saved Jacobian.
      std::memcpy(vals, fresh_vals.data(), sizeof(double) * fresh_vals.size());
      const double d = cj - fresh_cj;
      const VectorXd& M = sys.mass();
      for (Index i = 0; i < n; ++i) {
        vals[ggl.q_diag[i]] += d;
        vals[ggl.v_diag[i]] += d * M[i];
      }
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
int res_fn(realtype t, N_Vector yy, N_Vector yp, N_Vector rr, void* data) {
  return static_cast<IdaIntegrator::Impl*>(data)->residual(t, yy, yp, rr);
}
int jac_fn(realtype t, realtype cj, N_Vector yy, N_Vector yp, N_Vector, SUNMatrix J, void* data, N_Vector, N_Vector,
           N_Vector) {
  return static_cast<IdaIntegrator::Impl*>(data)->jacobian(t, cj, yy, yp, J);
}
// Timing wrappers around KLU's setup (factorisation) and solve.
IdaIntegrator::Impl* g_timed = nullptr;  // one integration at a time per process
int timed_setup(SUNLinearSolver S, SUNMatrix A) {
  if (!SUNLinSol_KLUGetSymbolic(S)) {
    // KLU's symbolic analysis happens inside SUNDIALS' first setup; to report it apart, the same
    // analysis (same ordering and options) is timed once on its own and discarded.
    klu_l_common c = *SUNLinSol_KLUGetCommon(S);
    const auto ta = Clock::now();
    klu_l_symbolic* sym = klu_l_analyze(SM_COLUMNS_S(A), SM_INDEXPTRS_S(A), SM_INDEXVALS_S(A), &c);
    g_timed->stats.symbolic_seconds += seconds_since(ta);
    if (sym) klu_l_free_symbolic(&sym, &c);
  }
  const auto t0 = Clock::now();
  const klu_l_numeric* before = SUNLinSol_KLUGetNumeric(S);
  const int r = g_timed->klu_setup(S, A);
  const double dt = seconds_since(t0);
  g_timed->stats.factor_seconds += dt;
  const klu_l_numeric* num = SUNLinSol_KLUGetNumeric(S);
  if (num != before) g_timed->stats.fresh_factorisations++;
  if (num) g_timed->stats.factor_nnz = static_cast<double>(num->lnz + num->unz);
  if (std::getenv("ISOCHOR_DEBUG_KLU"))
    std::fprintf(stderr, "klu setup %.3f s, fresh %d, L+U %ld, rcond %.2e\n", dt, num != before,
                 num ? static_cast<long>(num->lnz + num->unz) : -1L, SUNLinSol_KLUGetCommon(S)->rcond);
  return r;
}
int timed_solve(SUNLinearSolver S, SUNMatrix A, N_Vector x, N_Vector b, realtype tol) {
  const auto t0 = Clock::now();
  const int r = g_timed->klu_solve(S, A, x, b, tol);
  g_timed->stats.solve_seconds += seconds_since(t0);
  return r;
}
// The reduced solver as a SUNLinearSolver of direct (matrix-based) type: it reads the filled GGL matrix.
SUNLinearSolver_Type reduced_type(SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; }
SUNLinearSolver_ID reduced_id(SUNLinearSolver) { return SUNLINEARSOLVER_CUSTOM; }
int reduced_initialize(SUNLinearSolver) { return SUNLS_SUCCESS; }
int reduced_setup(SUNLinearSolver S, SUNMatrix A) {
  auto* s = static_cast<IdaIntegrator::Impl*>(S->content);
  const auto t0 = Clock::now();
  double cj = 0;
  IDAGetCurrentCj(s->ida_mem, &cj);
  const bool ok = s->reduced->setup(cj, SM_DATA_S(A));
  s->stats.factor_seconds += seconds_since(t0);
  s->stats.fresh_factorisations++;
  s->stats.factor_nnz = s->reduced->factor_nnz();
  s->stats.symbolic_seconds = s->reduced->analyse_seconds();
  return ok ? SUNLS_SUCCESS : SUNLS_PACKAGE_FAIL_REC;  // not positive definite: retry smaller step
}
int reduced_solve(SUNLinearSolver S, SUNMatrix, N_Vector x, N_Vector b, realtype) {
  auto* s = static_cast<IdaIntegrator::Impl*>(S->content);
  const auto t0 = Clock::now();
  const bool ok = s->reduced->solve(N_VGetArrayPointer(b), N_VGetArrayPointer(x));
  s->stats.solve_seconds += seconds_since(t0);
  s->stats.linear_iterations = s->reduced->iterations();
  s->stats.linear_fallbacks = s->reduced->fallbacks();
  return ok ? SUNLS_SUCCESS : SUNLS_PACKAGE_FAIL_REC;  // PCG did not converge: IDA retries a smaller step
}
sunindextype reduced_lastflag(SUNLinearSolver) { return 0; }
int reduced_free(SUNLinearSolver S) {
  S->content = nullptr;
  SUNLinSolFreeEmpty(S);
  return SUNLS_SUCCESS;
}

}  // namespace

IdaIntegrator::IdaIntegrator(ConstrainedSystem& system, IdaOptions options) : impl_(new Impl(system, std::move(options))) {}
IdaIntegrator::~IdaIntegrator() { delete impl_; }

void IdaIntegrator::consistent_initial_state(ConstrainedSystem& sys, double t0, VectorXd& q, VectorXd& v, VectorXd& a,
                                             VectorXd& lambda) {
  const Index n = sys.num_dofs(), m = sys.num_constraints();
  sys.initial_state(t0, q, v);
  const VectorXd& M = sys.mass();
  const VectorXd Minv = M.cwiseInverse();
  std::vector<std::vector<double>> G(m);
  for (Index j = 0; j < m; ++j) G[j].resize(sys.constraint_rows()[j].size());
  auto sparse_G = [&]() {
    std::vector<Eigen::Triplet<double>> tr;
    for (Index j = 0; j < m; ++j)
      for (std::size_t k = 0; k < G[j].size(); ++k) tr.emplace_back(j, sys.constraint_rows()[j][k], G[j][k]);
    Eigen::SparseMatrix<double> S(m, n);
    S.setFromTriplets(tr.begin(), tr.end());
    return S;
  };
  VectorXd g(m), gt(m);
  if (m > 0) {
    // 1. Positions onto g = 0: minimum-norm (mass-weighted) Newton steps.
    for (int it = 0; it < 50; ++it) {
      sys.constraint(t0, q, g);
      sys.constraint_jacobian(t0, q, G, nullptr);
      if (g.norm() < 1e-14 * (1.0 + q.norm())) break;
      const Eigen::SparseMatrix<double> S = sparse_G();
      const Eigen::SparseMatrix<double> A = S * Minv.asDiagonal() * S.transpose();
      Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(A);
      q -= Minv.asDiagonal() * (S.transpose() * ldlt.solve(g));
    }
    // 2. Velocities: [M G^T; G 0][v; nu] = [M v0; -g_t].
    sys.constraint_jacobian(t0, q, G, &gt);
    const Eigen::SparseMatrix<double> S = sparse_G();
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(Eigen::SparseMatrix<double>(S * Minv.asDiagonal() * S.transpose()));
    v -= Minv.asDiagonal() * (S.transpose() * ldlt.solve(VectorXd(S * v + gt)));
    // 3. Accelerations: M a + G^T lambda = f, G a = -w, where w = d/dt (G v + g_t) at a = 0,
    //    taken by a central difference along x(t +- h) = x +- h v (drivers exact).
    VectorXd f(n);
    sys.force(t0, q, v, f);
    const double h = 1e-6 * std::max(1.0, std::abs(t0));
    auto velocity_constraint = [&](double t, const VectorXd& qq) {
      std::vector<std::vector<double>> Gh(G);
      VectorXd gth(m);
      sys.constraint_jacobian(t, qq, Gh, &gth);
      VectorXd out = gth;
      for (Index j = 0; j < m; ++j)
        for (std::size_t k = 0; k < Gh[j].size(); ++k) out[j] += Gh[j][k] * v[sys.constraint_rows()[j][k]];
      return out;
    };
    const VectorXd w = (velocity_constraint(t0 + h, q + h * v) - velocity_constraint(t0 - h, q - h * v)) / (2 * h);
    lambda = ldlt.solve(VectorXd(S * Minv.cwiseProduct(f) + w));
    a = Minv.cwiseProduct(f - S.transpose() * lambda);
  } else {
    VectorXd f(n);
    sys.force(t0, q, v, f);
    a = Minv.cwiseProduct(f);
    lambda.resize(0);
  }
}

IdaStats IdaIntegrator::run(const std::vector<double>& times, const FrameCallback& on_frame) {
  Impl& s = *impl_;
  const auto wall0 = Clock::now();
  const Index n = s.n, m = s.m, N = 2 * n + 2 * m;
  const double t0 = times.front();
  VectorXd q0, v0, a0, l0;
  consistent_initial_state(s.sys, t0, q0, v0, a0, l0);

  SUNContext_Create(nullptr, &s.ctx);
  N_Vector yy = N_VNew_Serial(N, s.ctx), yp = N_VNew_Serial(N, s.ctx), id = N_VNew_Serial(N, s.ctx),
           atol = N_VNew_Serial(N, s.ctx);
  double* y = N_VGetArrayPointer(yy);
  double* d = N_VGetArrayPointer(yp);
  Eigen::Map<VectorXd>(y, N).setZero();
  Eigen::Map<VectorXd>(d, N).setZero();
  Eigen::Map<VectorXd>(y, n) = q0;
  Eigen::Map<VectorXd>(y + n, n) = v0;
  if (m) Eigen::Map<VectorXd>(y + 2 * n, m) = l0;
  Eigen::Map<VectorXd>(d, n) = v0;
  Eigen::Map<VectorXd>(d + n, n) = a0;
  double* idv = N_VGetArrayPointer(id);
  double* av = N_VGetArrayPointer(atol);
  const double atol_v = s.opt.atol_v > 0 ? s.opt.atol_v : 100.0 * s.opt.atol_q;
  const double atol_l = s.opt.atol_lambda > 0 ? s.opt.atol_lambda : 1e-6 * s.sys.force_scale();
  for (Index i = 0; i < N; ++i) {
    idv[i] = i < 2 * n ? 1.0 : 0.0;
    av[i] = i < n ? s.opt.atol_q : i < 2 * n ? atol_v : atol_l;
  }
  // mu multiplies G^T in the velocity equation: its natural scale is atol_v / |G_j|.
  if (m) {
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

  void* mem = IDACreate(s.ctx);
  s.ida_mem = mem;
  IDAInit(mem, res_fn, t0, yy, yp);
  IDASVtolerances(mem, s.opt.rtol, atol);
  IDASetUserData(mem, &s);
  IDASetId(mem, id);
  IDASetSuppressAlg(mem, SUNTRUE);
  IDASetNonlinConvCoef(mem, s.opt.newton_coef);
  IDASetMaxOrd(mem, s.opt.max_order);
  if (s.opt.max_step > 0) IDASetMaxStep(mem, s.opt.max_step);
  if (s.opt.initial_step > 0) {
    IDASetInitStep(mem, s.opt.initial_step);
  } else if (a0.size() > 0 && times.back() > t0) {
    // IDA's own first step, 0.5 / |y'|, is set by the accelerations over the velocity tolerance:
    // with tight tolerances it is ~1e-10 s, where the GGL matrix (c^2 M against the constraint
    // rows) is too ill-conditioned for Newton to converge (a fixed-bottom cube failed at t = 0 for
    // rtol <= 1e-6). A position-based first step instead: the error 1/2 a h^2 of a first step
    // equals the position tolerance, h0 = sqrt(2 / |a|_wrms).
    double sum = 0;
    for (Index i = 0; i < n; ++i) {
      const double w = a0[i] / (s.opt.rtol * std::abs(q0[i]) + s.opt.atol_q);
      sum += w * w;
    }
    const double anorm = std::sqrt(sum / static_cast<double>(std::max<Index>(n, 1)));
    if (anorm > 0) {
      double h0 = std::min(std::sqrt(2.0 / anorm), 1e-3 * (times.back() - t0));
      if (s.opt.max_step > 0) h0 = std::min(h0, s.opt.max_step);
      IDASetInitStep(mem, h0);
    }
  }
  IDASetStopTime(mem, times.back());
  IDASetMaxNumSteps(mem, 100000);
  SUNMatrix J = SUNSparseMatrix(N, N, s.ggl.pattern().nnz(), CSC_MAT, s.ctx);
  if (s.reduced) {
    s.LS = SUNLinSolNewEmpty(s.ctx);
    s.LS->content = &s;
    s.LS->ops->gettype = reduced_type;
    s.LS->ops->getid = reduced_id;
    s.LS->ops->initialize = reduced_initialize;
    s.LS->ops->setup = reduced_setup;
    s.LS->ops->solve = reduced_solve;
    s.LS->ops->lastflag = reduced_lastflag;
    s.LS->ops->free = reduced_free;
  } else {
    s.LS = SUNLinSol_KLU(yy, J, s.ctx);
    if (s.opt.ordering == "metis") {
      use_klu_order(s.LS, &s.order);
    } else {
      SUNLinSol_KLUSetOrdering(s.LS, s.opt.ordering == "amd" ? 0 : 1);
    }
    s.klu_setup = s.LS->ops->setup;
    s.klu_solve = s.LS->ops->solve;
    s.LS->ops->setup = timed_setup;
    s.LS->ops->solve = timed_solve;
  }
  g_timed = &s;
  IDASetLinearSolver(mem, s.LS, J);
  IDASetJacFn(mem, jac_fn);

  auto collect = [&]() {
    IDAGetNumSteps(mem, &s.stats.steps);
    IDAGetNumResEvals(mem, &s.stats.residual_evals);
    IDAGetNumLinSolvSetups(mem, &s.stats.linear_setups);
    IDAGetNumNonlinSolvIters(mem, &s.stats.newton_iterations);
    IDAGetNumNonlinSolvConvFails(mem, &s.stats.newton_failures);
    IDAGetNumErrTestFails(mem, &s.stats.error_test_failures);
    int order = 0;
    double h = 0;
    IDAGetLastOrder(mem, &order);
    IDAGetLastStep(mem, &h);
    s.stats.frames.push_back({s.stats.steps, s.stats.newton_iterations, s.stats.error_test_failures,
                              s.stats.newton_failures, s.stats.jacobian_evals, order, h});
  };
  auto cleanup = [&]() {
    IDAFree(&mem);
    SUNLinSolFree(s.LS);
    SUNMatDestroy(J);
    N_VDestroy(yy);
    N_VDestroy(yp);
    N_VDestroy(id);
    N_VDestroy(atol);
    SUNContext_Free(&s.ctx);
    g_timed = nullptr;
  };

  N_Vector yout = N_VClone(yy);
  double tcur = t0;
  std::size_t k = 0;
  try {
    while (k < times.size()) {
      if (times[k] <= tcur) {
        const double tf = times[k];
        if (tf == tcur) {  // a step ended on the frame (the stop time below): no interpolation
          N_VScale(1.0, yy, yout);
        } else if (IDAGetDky(mem, tf, 0, yout) < 0) {
          throw IntegrationError(tf, "IDAGetDky could not interpolate the frame");
        }
        const double* yo = N_VGetArrayPointer(yout);
        collect();
        on_frame(static_cast<int>(k), tf, Eigen::Map<const VectorXd>(yo, n), Eigen::Map<const VectorXd>(yo + n, n),
                 Eigen::Map<const VectorXd>(yo + 2 * n, m), s.stats.frames.back());
        ++k;
        continue;
      }
      // Steps end on every frame time, so that frames are solution points: an interpolated frame
      // keeps the zone volumes only to the interpolation error (1e-7 of a zone on the rigged arm).
      IDASetStopTime(mem, times[k]);
      double tret = tcur;
      const int flag = IDASolve(mem, times[k], &tret, yy, yp, IDA_ONE_STEP);
      if (flag < 0) {
        char* name = IDAGetReturnFlagName(flag);
        std::string reason = name ? name : "unknown IDA failure";
        free(name);
        throw IntegrationError(tret, reason);
      }
      tcur = tret;
      long steps = 0;
      IDAGetNumSteps(mem, &steps);
      if (steps > s.opt.max_steps)
        throw IntegrationError(tcur, "more than " + std::to_string(s.opt.max_steps) + " steps (integrator.max_steps)");
    }
  } catch (...) {
    N_VDestroy(yout);
    s.stats.wall_seconds = seconds_since(wall0);
    cleanup();
    throw;
  }
  N_VDestroy(yout);
  s.stats.wall_seconds = seconds_since(wall0);
  cleanup();
  return s.stats;
}

}  // namespace isochor
