#include "isochor/integrators/statics.hpp"

#include <functional>
#include "bordered.hpp"
#include "kkt.hpp"
#include "klu_order.hpp"
#include "sundials_util.hpp"
#include "timing.hpp"

#include "isochor/integrators/initial_state.hpp"
#include "isochor/integrators/interrupt.hpp"

#include <kinsol/kinsol.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>

namespace isochor {

struct StaticSolver::Impl {
  ConstrainedSystem& sys;
  StaticOptions opt;
  Index n, m;
  KktLayout kkt;  // (n + m) KKT pattern and slots
  std::vector<double> K;
  std::vector<std::vector<double>> G;
  VectorXd q, v0, lambda, f, g;
  double t = 0;
  RunStats stats;
  // Between begin() and finish(): the frames, the callback and the next frame to solve.
  std::vector<double> times;
  FrameCallback on_frame;
  std::size_t next = 0;
  bool running = false;
  // SUNDIALS' objects of the run, released in reverse order (KINSOL's memory first).
  struct KinFree {
    void operator()(void* mem) const { KINFree(&mem); }
  };
  sun::Context context;
  sun::Vector u, uscale, fscale;
  sun::Matrix J;
  sun::LinearSolver LS;
  std::unique_ptr<void, KinFree> kin;
  SUNContext ctx = nullptr;
  void* mem = nullptr;
  std::exception_ptr caught;                 // thrown inside a callback, rethrown when KINSOL returns
  std::vector<Index> order;                  // METIS order for KLU
  std::unique_ptr<BorderedSolver> bordered;  // reduced/krylov: A = K + H_lambda and the borders

  Impl(ConstrainedSystem& s, StaticOptions o)
      : sys(s),
        opt(o),
        n((check_system(s), s.num_dofs())),
        m(s.num_constraints()),
        kkt(s.pattern(), s.constraint_rows()) {
    const SparsePattern& S = sys.pattern();
    G.resize(m);
    for (Index j = 0; j < m; ++j) G[j].resize(sys.constraint_rows()[j].size());
    K.resize(S.nnz());
    v0 = VectorXd::Zero(n);
    f.resize(n);
    g.resize(m);
    if (opt.linear_solver != LinearSolverKind::klu)
      bordered = std::make_unique<BorderedSolver>(S, sys.constraint_rows(), symmetric_solver_of(opt.linear_solver));
    else
      check_groups(sys, "statics' KLU (METIS ordering)");
  }

  int residual(N_Vector u, N_Vector fv) {
    const auto t0 = Clock::now();
    const double* x = N_VGetArrayPointer(u);
    double* r = N_VGetArrayPointer(fv);
    q = Eigen::Map<const VectorXd>(x, n);
    lambda = Eigen::Map<const VectorXd>(x + n, m);
    sys.force(t, q, v0, f);
    Eigen::Map<VectorXd> Rq(r, n), Rg(r + n, m);
    Rq = -f;
    add_constraint_terms(sys, t, q, lambda, G, g, r);
    if (m) Rg = g;
    stats.residual_evals++;
    stats.assembly_seconds += seconds_since(t0);
    return Rq.allFinite() ? 0 : 1;
  }

  int jacobian(N_Vector u, SUNMatrix J) {
    const auto t0 = Clock::now();
    const double* x = N_VGetArrayPointer(u);
    q = Eigen::Map<const VectorXd>(x, n);
    lambda = Eigen::Map<const VectorXd>(x + n, m);
    std::memcpy(SM_INDEXPTRS_S(J), kkt.p.col_ptr.data(), sizeof(sunindextype) * (kkt.p.n + 1));
    std::memcpy(SM_INDEXVALS_S(J), kkt.p.row_ind.data(), sizeof(sunindextype) * kkt.p.nnz());
    std::fill(K.begin(), K.end(), 0.0);
    sys.add_force_jacobians(t, q, v0, K.data(), nullptr);
    if (m) {
      sys.add_constraint_hessian(t, q, lambda, 1.0, K.data());
      sys.constraint_jacobian(t, q, G, nullptr);
    }
    if (!bordered) kkt.fill(K.data(), G, SM_DATA_S(J));  // the bordered solver reads K and G
    stats.jacobian_evals++;
    stats.assembly_seconds += seconds_since(t0);
    return 0;
  }
};

namespace {
#if SUNDIALS_VERSION_MAJOR < 7
void kin_quiet(int, const char*, const char*, char*, void*) {}  // failures are reported by the caller
#endif
int kin_res(N_Vector u, N_Vector f, void* data) {
  auto& s = *static_cast<StaticSolver::Impl*>(data);
  return guarded(s.caught, [&] { return s.residual(u, f); });
}
int kin_jac(N_Vector u, N_Vector, SUNMatrix J, void* data, N_Vector, N_Vector) {
  auto& s = *static_cast<StaticSolver::Impl*>(data);
  return guarded(s.caught, [&] { return s.jacobian(u, J); });
}
// The bordered solver as a matrix-based SUNLinearSolver: setup factors A = K + H_lambda and the
// borders that the Jacobian function just assembled; the KKT matrix itself is not filled.
int bordered_setup(SUNLinearSolver LS, SUNMatrix) {
  auto& s = *static_cast<StaticSolver::Impl*>(LS->content);
  return guarded(s.caught, [&] {
    const auto t0 = Clock::now();
    const bool ok = s.bordered->factor(s.K.data()) && s.bordered->set_borders(s.G);
    s.stats.factor_seconds += seconds_since(t0);
    s.stats.fresh_factorisations++;
    s.stats.factor_nnz = s.bordered->symmetric().factor_nnz();
    s.stats.linear_fallbacks = s.bordered->kkt_fallbacks();
    s.stats.symbolic_seconds = s.bordered->symmetric().analyse_seconds();
    return ok ? sun::kSuccess : sun::kLinearFailUnrecoverable;
  });
}
int bordered_solve(SUNLinearSolver LS, SUNMatrix, N_Vector x, N_Vector b, sunrealtype) {
  auto& s = *static_cast<StaticSolver::Impl*>(LS->content);
  return guarded(s.caught, [&] {
    const auto t0 = Clock::now();
    const double* r = N_VGetArrayPointer(b);
    double* y = N_VGetArrayPointer(x);
    const bool ok = s.bordered->solve(r, r + s.n, y, y + s.n);
    s.stats.solve_seconds += seconds_since(t0);
    s.stats.linear_iterations = s.bordered->symmetric().iterations() + s.bordered->border_iterations();
    s.stats.linear_fallbacks = s.bordered->kkt_fallbacks();
    return ok ? sun::kSuccess : sun::kLinearFailUnrecoverable;
  });
}
}  // namespace

// linear_solver = "auto" for statics: KLU on the KKT matrix, but above 64 constraint rows (1-ring
// zones, fine patches, rollers: one row per node) `reduced`, whose sparse border
// (integrators/src/bordered.hpp) factors A + G^T D G with CHOLMOD's supernodal Cholesky where KLU
// factors the KKT matrix without BLAS-3. Measured (bench/zones_cost.sh, docs/results/zones_cost.md,
// one thread, medians of 3), Cook's membrane (a roller row on every node) at N = 32, 12,974 tets:
// 17.3 s on KLU against 3.2 s with the rows alone, 99.3 s against 12.7 s with 3,267 1-ring zones;
// at N = 64, 97,802 tets, 1,134 s against 47 s with the rows alone. At most 64 rows the dense
// border would need A alone to be definite and m + 1 solves per setup: KLU stays.
LinearSolverKind automatic_static_solver(const ConstrainedSystem& system) {
  return system.dofs_per_group() == 3 && system.num_constraints() > BorderedSolver::kDenseBorderMax
             ? LinearSolverKind::reduced
             : LinearSolverKind::klu;
}

namespace {
using Impl = StaticSolver::Impl;

// KINSOL on the (n + m) KKT system from the initial state: unknowns u = (q, lambda), forces
// measured against the system's force scale and constraint rows against theirs (volumes), exact
// Newton (a fresh Jacobian every iteration), KLU in METIS's order or the bordered solver.
void setup_kinsol(Impl& s, double t0) {
  const Index N = s.n + s.m;
  s.context = sun::make_context(t0, /*quiet=*/true);  // failures are reported by the caller
  s.ctx = s.context.get();
  s.u = new_serial_vector(N, s.ctx);
  s.uscale = new_serial_vector(N, s.ctx);
  s.fscale = new_serial_vector(N, s.ctx);
  VectorXd q0, v0dummy;
  s.sys.initial_state(t0, q0, v0dummy);
  double* x = N_VGetArrayPointer(s.u.get());
  Eigen::Map<VectorXd>(x, N).setZero();
  Eigen::Map<VectorXd>(x, s.n) = q0;
  N_VConst(1.0, s.uscale.get());
  double* fs = N_VGetArrayPointer(s.fscale.get());
  for (Index i = 0; i < N; ++i)
    fs[i] = i < s.n ? 1.0 / s.sys.force_scale() : 1.0 / s.sys.constraint_scale(static_cast<int>(i - s.n));
  s.kin.reset(check_ptr(KINCreate(s.ctx), "KINCreate"));
  void* mem = s.mem = s.kin.get();
  check(KINInit(mem, kin_res, s.u.get()), "KINInit", t0);
  check(KINSetUserData(mem, &s), "KINSetUserData", t0);
#if SUNDIALS_VERSION_MAJOR < 7
  check(KINSetErrHandlerFn(mem, kin_quiet, nullptr), "KINSetErrHandlerFn", t0);
#endif
  check(KINSetFuncNormTol(mem, s.opt.residual_tol), "KINSetFuncNormTol", t0);
  check(KINSetScaledStepTol(mem, 1e-14), "KINSetScaledStepTol", t0);
  check(KINSetMaxSetupCalls(mem, 1), "KINSetMaxSetupCalls", t0);
  check(KINSetNumMaxIters(mem, s.opt.max_iterations), "KINSetNumMaxIters", t0);
  check(KINSetMaxNewtonStep(mem, 1e10), "KINSetMaxNewtonStep", t0);
  s.J.reset(check_ptr(SUNSparseMatrix(N, N, s.kkt.p.nnz(), CSC_MAT, s.ctx), "SUNSparseMatrix"));
  if (s.bordered) {
    s.LS = make_custom_linear_solver(s.ctx, &s, bordered_setup, bordered_solve);
  } else {
    s.LS.reset(check_ptr(SUNLinSol_KLU(s.u.get(), s.J.get(), s.ctx), "SUNLinSol_KLU"));
    s.order = metis_order(s.sys.pattern(), s.sys.dofs_per_group(), s.n, 1, s.sys.constraint_rows(), 1);
    use_klu_order(s.LS.get(), &s.order);
  }
  check(KINSetLinearSolver(mem, s.LS.get(), s.J.get()), "KINSetLinearSolver", t0);
  check(KINSetJacFn(mem, kin_jac), "KINSetJacFn", t0);
}

// KINSOL's solve from u with this strategy; its iterations counted. Rethrows what a callback threw.
int kinsol(Impl& s, int strategy) {
  const int flag = KINSol(s.mem, s.u.get(), strategy, s.uscale.get(), s.fscale.get());
  rethrow_caught(s.caught);
  long iters = 0;
  check(KINGetNumNonlinSolvIters(s.mem, &iters), "KINGetNumNonlinSolvIters", s.t);
  s.stats.newton_iterations += iters;
  return flag;
}

// Equilibrium at pseudo-time `to` from the one in u: full Newton steps first (the merit function
// |F| of a KKT system often rises on a step that converges; measured: the cantilever's first load
// increment takes 4 full steps and 116 line-searched ones), then from the same start with
// KINSOL's line search. Returns KINSOL's flag and the residual norm; u is the start again on
// failure.
int solve_at(Impl& s, double to, double& fnorm) {
  s.t = to;
  const Index N = s.n + s.m;
  auto solution = [&] { return Eigen::Map<VectorXd>(N_VGetArrayPointer(s.u.get()), N); };
  const VectorXd start = solution();
  check(KINSetNumMaxIters(s.mem, std::min<long>(s.opt.max_iterations, 40)), "KINSetNumMaxIters", s.t);
  int flag = kinsol(s, KIN_NONE);
  if (flag < 0 || !solution().allFinite()) {
    s.stats.newton_failures++;
    solution() = start;
    check(KINSetNumMaxIters(s.mem, s.opt.max_iterations), "KINSetNumMaxIters", s.t);
    flag = kinsol(s, KIN_LINESEARCH);
  }
  check(KINGetFuncNorm(s.mem, &fnorm), "KINGetFuncNorm", s.t);
  s.stats.steps++;
  if (flag < 0 || !solution().allFinite()) {
    solution() = start;
    if (flag >= 0) flag = KIN_SYSFUNC_FAIL;
  }
  return flag;
}

// The increment from `from` to `to`, halved on failure up to substeps_on_failure levels (an
// interrupt is taken before each part, so a long halving does not hold it up).
void increment(Impl& s, double from, double to, int depth) {
  step_boundary(from);
  double fnorm = 0;
  const int flag = solve_at(s, to, fnorm);
  if (flag >= 0) return;
  if (depth < s.opt.substeps_on_failure) {
    s.stats.step_halvings++;
    increment(s, from, 0.5 * (from + to), depth + 1);
    increment(s, 0.5 * (from + to), to, depth + 1);
    return;
  }
  char* name = KINGetReturnFlagName(flag);
  std::string reason = std::string(name ? name : "KINSOL failure") + ", scaled residual " + std::to_string(fnorm);
  if (s.opt.substeps_on_failure > 0)
    reason += " (from pseudo-time " + std::to_string(from) + ", after " + std::to_string(depth) +
              " halvings of the increment)";
  free(name);
  throw IntegrationError(to, reason);
}

// Releases SUNDIALS' objects of the run (KINSOL's memory first, the context last).
void release(Impl& s) {
  s.kin.reset();
  s.LS.reset();
  s.J.reset();
  for (sun::Vector* v : {&s.u, &s.uscale, &s.fscale}) v->reset();
  s.context.reset();
  s.ctx = nullptr;
  s.mem = nullptr;
}
}  // namespace

StaticSolver::StaticSolver(ConstrainedSystem& system, StaticOptions options)
    : impl_(std::make_unique<Impl>(system, options)) {}
StaticSolver::~StaticSolver() = default;

RunStats StaticSolver::run(const std::vector<double>& times, const FrameCallback& on_frame) {
  begin(times, on_frame);
  step(times.back());
  return finish();
}

namespace {
// Solves frame k of the run from the previous frame's solution and delivers it.
void solve_frame(StaticSolver::Impl& s, std::size_t k) {
  increment(s, k > 0 ? s.times[k - 1] : s.times.front(), s.times[k], 0);
  double fnorm = 0;
  check(KINGetFuncNorm(s.mem, &fnorm), "KINGetFuncNorm", s.t);
  s.stats.frames.push_back(
      {s.stats.steps, s.stats.newton_iterations, 0, s.stats.newton_failures, s.stats.jacobian_evals, 0, fnorm});
  const double* y = N_VGetArrayPointer(s.u.get());
  s.on_frame(static_cast<int>(k), s.t, Eigen::Map<const VectorXd>(y, s.n), s.v0,
             Eigen::Map<const VectorXd>(y + s.n, s.m), s.stats.frames.back());
}
// Runs `work`, adding its wall time to the run's; on an exception KINSOL is released first.
template <class Work>
void timed_or_released(StaticSolver::Impl& s, Work&& work) {
  const auto wall0 = Clock::now();
  try {
    work();
  } catch (...) {
    s.stats.wall_seconds += seconds_since(wall0);
    s.running = false;
    release(s);
    throw;
  }
  s.stats.wall_seconds += seconds_since(wall0);
}
}  // namespace

void StaticSolver::begin(const std::vector<double>& times, const FrameCallback& on_frame) {
  Impl& s = *impl_;
  s.times = times;
  s.on_frame = on_frame;
  s.next = 0;
  s.stats.wall_seconds = 0;
  timed_or_released(s, [&] {
    setup_kinsol(s, times.front());
    s.running = true;
    solve_frame(s, s.next++);
  });
}

// Statics has no steps between frames: the time reached is the last frame solved.
double StaticSolver::step(double t_out) {
  Impl& s = *impl_;
  if (!s.running) throw Error("statics: step() before begin()");
  const double target = std::min(t_out, s.times.back());
  timed_or_released(s, [&] {
    while (s.next < s.times.size() && s.times[s.next - 1] < target) solve_frame(s, s.next++);
  });
  return s.times[s.next - 1];
}

RunStats StaticSolver::finish() {
  Impl& s = *impl_;
  if (s.running) release(s);
  s.running = false;
  return s.stats;
}

}  // namespace isochor
