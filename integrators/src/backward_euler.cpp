#include "isochor/integrators/backward_euler.hpp"
#include "timing.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <stdexcept>

#include "isochor/integrators/fixed_step.hpp"
#include "isochor/integrators/initial_state.hpp"
#include "isochor/integrators/sparse_factor.hpp"
#include "isochor/base/error.hpp"
#include "bordered.hpp"
#include "kkt.hpp"

namespace isochor {

namespace {
// The constraint rows up to which the border is dense: the option's, and on MPI ranks at least
// kRanksDenseBorderMax (the KKT matrix is factored on one process).
int dense_border_max(const ConstrainedSystem& s, const BackwardEulerOptions& o) {
  return s.partition() ? std::max(o.schur_max_constraints, BackwardEulerOptions::kRanksDenseBorderMax)
                       : o.schur_max_constraints;
}
}  // namespace

struct BackwardEuler::Impl {
  ConstrainedSystem& sys;
  BackwardEulerOptions opt;
  Index n, m;
  // The step matrix and the borders by a Schur complement: S is solvers[0] (CHOLMOD) or
  // solvers[1] (PCG, or AMG when named); "auto" with the line search may switch between them.
  std::unique_ptr<BorderedSolver> solvers[2];
  BorderedSolver* S = nullptr;
  bool refuse_indefinite = false;  // the line search shifts indefinite matrices (run() sets both)
  std::vector<double> K, D, Sv;
  std::vector<Index> diag;
  std::vector<std::vector<double>> G;
  RunStats stats;
  std::unique_ptr<FixedStepper> stepper;  // between begin() and finish()
  // Many constraints: KLU on the whole KKT matrix instead of m solves for a dense Schur complement.
  bool use_kkt;
  std::unique_ptr<KktLayout> layout;
  std::unique_ptr<KktFactor> kkt;
  std::vector<double> kv;

  Impl(ConstrainedSystem& s, BackwardEulerOptions o)
      : sys(s),
        opt(o),
        n((check_system(s), s.num_dofs())),
        m(s.num_constraints()),
        use_kkt(o.linear_solver == LinearSolverKind::klu || m > dense_border_max(s, o)) {
    if (use_kkt && s.partition())
      throw Error("backward Euler: " + std::to_string(m) + " constraint rows (more than " +
                  std::to_string(dense_border_max(s, o)) +
                  ") take KLU on the whole KKT matrix, which runs on one process (on MPI ranks: fewer zones, or "
                  "integrator.kind = \"ida\")");
    if (o.project_hessian && !s.set_hessian_projection(true))
      throw Error("integrator.hessian = \"projected\": this model has no element Hessians to project");
    if (use_kkt) {
      check_groups(s, "backward Euler's KKT matrix (KLU, METIS ordering)");
      layout = std::make_unique<KktLayout>(s.pattern(), s.constraint_rows());
      kkt = std::make_unique<KktFactor>(*layout, s.pattern(), s.dofs_per_group(), s.constraint_rows());
      kv.resize(layout->p.nnz());
      work.kr.resize(n + m);
    }
    const SparsePattern& p = sys.pattern();
    K.resize(p.nnz());
    D.resize(p.nnz());
    Sv.resize(p.nnz());
    diag.resize(n);
    for (Index i = 0; i < n; ++i) diag[i] = p.find(i, i);
    G.resize(m);
    for (Index j = 0; j < m; ++j) G[j].resize(sys.constraint_rows()[j].size());
  }

  BorderedSolver& step_solver(LinearSolverKind kind) {  // made on first use
    std::unique_ptr<BorderedSolver>& b = solvers[kind == LinearSolverKind::reduced ? 0 : 1];
    if (!b) {
      b = std::make_unique<BorderedSolver>(
          sys.pattern(), sys.constraint_rows(), symmetric_solver_of(kind),
          opt.linear_tol > 0 ? opt.linear_tol : BackwardEulerOptions::kDefaultLinearTol, sys.partition());
      if (refuse_indefinite) b->refuse_indefinite();
    }
    return *b;
  }
  void make_step_solver(LinearSolverKind kind) {  // S from here on; the next iteration factors afresh
    S = &step_solver(kind);
    factored = false;
    refresh = true;
    buying = false;
  }
  // Over both solvers: CG iterations, and seconds of CHOLMOD's ordering and symbolic analysis.
  long linear_iterations() const {
    long k = 0;
    for (const auto& b : solvers)
      if (b) k += b->symmetric().iterations();
    return k;
  }
  double analyse_seconds() const {
    double t = 0;
    for (const auto& b : solvers)
      if (b) t += b->symmetric().analyse_seconds();
    return t;
  }

  // linear_solver = "auto" with the line search: after every step, once the current solver has
  // taken kChooseWindow steps, the cost per Newton iteration of each solver is estimated from
  // what those steps counted (no clock, so a run is repeatable): PCG's from its CG iterations,
  // CHOLMOD's from the fresh matrices per Newton iteration and its factor's flops and entries
  // (the symbolic analysis; above kAnalyseAnyMaxDofs, where it costs more than ~0.1 s, asked for
  // only once CG takes kAnalyseMinCg iterations per Newton iteration). The solver switches when
  // the other is estimated kSwitchGain times cheaper.
  // Seconds per unit, measured on one core of the 2-core development machine: a CG
  // iteration per entry of the step matrix; a factorisation per flop and per entry of the factor;
  // a solve per entry of the factor.
  static constexpr double kCgSecondsPerEntry = 0.3e-9, kFactorSecondsPerFlop = 0.05e-9, kFactorSecondsPerEntry = 2e-9,
                          kSolveSecondsPerEntry = 1e-9;
  // Per Newton iteration: CG's iterations (the borders' solves included) or CHOLMOD's 1 + m solves;
  // per factorisation.
  double pcg_solve_cost(double cg) const { return cg * static_cast<double>(sys.pattern().nnz()) * kCgSecondsPerEntry; }
  double cholmod_solve_cost(double entries) const {
    return static_cast<double>(1 + m) * entries * kSolveSecondsPerEntry;
  }
  static double cholmod_factor_cost(double flops, double entries) {
    return flops * kFactorSecondsPerFlop + entries * kFactorSecondsPerEntry;
  }
  static constexpr int kChooseWindow = 4;
  static constexpr double kAnalyseMinCg = 100, kSwitchGain = 1.5;
  static constexpr Index kAnalyseAnyMaxDofs = 20000;
  bool choosing = false;
  struct StepCounts {
    long newton, fresh, cg, bought;  // bought: fresh matrices the reuse rule bought (charge_reuse)
  };
  std::vector<StepCounts> recent;  // per step since the solver last changed (the last kChooseWindow)
  double cg_per_newton = -1;       // PCG's CG iterations per Newton iteration over its last window
  StepCounts counts() const {
    return {stats.newton_iterations, stats.fresh_factorisations, stats.linear_iterations, bought};
  }
  void after_step(const StepCounts& before) {
    const StepCounts now = counts();
    recent.push_back(
        {now.newton - before.newton, now.fresh - before.fresh, now.cg - before.cg, now.bought - before.bought});
    if (static_cast<int>(recent.size()) > kChooseWindow) recent.erase(recent.begin());
    if (static_cast<int>(recent.size()) < kChooseWindow) return;
    StepCounts w{0, 0, 0, 0};
    for (const StepCounts& c : recent) w = {w.newton + c.newton, w.fresh + c.fresh, w.cg + c.cg, w.bought + c.bought};
    if (w.newton == 0) return;
    const bool on_pcg = S == solvers[1].get();
    // CHOLMOD's fresh matrices per Newton iteration: on PCG, those the contraction asked for (the
    // reuse rule buys more there, where a matrix costs only its assembly, than it would on CHOLMOD).
    const double fresh = static_cast<double>(on_pcg ? w.fresh - w.bought : w.fresh) / static_cast<double>(w.newton);
    if (on_pcg) cg_per_newton = static_cast<double>(w.cg) / static_cast<double>(w.newton);
    if (cg_per_newton < 0) return;                                                  // PCG never ran
    if (on_pcg && cg_per_newton < kAnalyseMinCg && n > kAnalyseAnyMaxDofs) return;  // CG cheap, the analysis not
    double flops = 0, entries = 0;
    const auto ta = Clock::now();  // the first call orders and analyses: part of the factorisations' time
    step_solver(LinearSolverKind::reduced).symmetric().factor_cost(flops, entries);
    stats.factor_seconds += seconds_since(ta);
    stats.symbolic_seconds = analyse_seconds();
    const double pcg = pcg_solve_cost(cg_per_newton);
    const double direct = fresh * cholmod_factor_cost(flops, entries) + cholmod_solve_cost(entries);
    if (on_pcg ? kSwitchGain * direct < pcg : kSwitchGain * pcg < direct) {
      make_step_solver(on_pcg ? LinearSolverKind::reduced : LinearSolverKind::krylov);
      recent.clear();
      stats.solver_switches++;
    }
  }

  // Factor reuse by cost. A matrix kept because it contracts at 1/4 or better may still take more
  // iterations per step than a fresh one would: in the CNH cube at 8 ms on "auto", the matrix
  // CHOLMOD factored at 0.072 s was kept to the end at 4-8 iterations per step, where the
  // CHOLMOD-only run kept one from 0.056 s at 2-3. The step that factored the matrix sets the
  // reference (its iterations from the factorisation on, at least 2); every later step's
  // iterations beyond it are charged at the estimated cost of one (the forces, and the solves of
  // pcg_solve_cost or cholmod_solve_cost), and once the charges exceed the estimated price of a
  // fresh matrix (the Hessian's assembly and, on CHOLMOD, the factorisation) the next step factors
  // afresh. Renting until the rent paid equals the price costs at most twice the better choice
  // in hindsight (the ski-rental rule). Counts only, no clock: a run repeats exactly. Not for
  // KLU's KKT matrix or AMG, which have no estimate.
  // Seconds per entry of the step matrix, one core of the 2-core development machine
  // (bench_assembly: the CNH ball's gradient pass 73 ns per tet, gradient and Hessian 586 ns, ~25
  // entries per tet; the line search's energy adds to the former).
  static constexpr double kForcesSecondsPerEntry = 4e-9, kHessianSecondsPerEntry = 20e-9;
  int reference_iterations = 2;
  double rent = 0;
  void charge_reuse(int iterations, int since_fresh, bool fresh_step, long cg) {
    if (fresh_step) {
      reference_iterations = std::max(2, since_fresh);
      rent = 0;
      return;
    }
    const int extra = iterations - reference_iterations;
    if (extra <= 0 || use_kkt || opt.linear_solver == LinearSolverKind::amg) return;
    const double entries_S = static_cast<double>(sys.pattern().nnz());
    double flops = 0, entries = 0;
    const bool direct = S->symmetric().factor_cost(flops, entries);
    const double iteration =
        entries_S * kForcesSecondsPerEntry +
        (direct ? cholmod_solve_cost(entries) : pcg_solve_cost(static_cast<double>(cg) / iterations));
    const double price = entries_S * kHessianSecondsPerEntry + (direct ? cholmod_factor_cost(flops, entries) : 0.0);
    rent += extra * iteration;
    if (rent > price && !refresh) refresh = buying = true;
  }
  bool buying = false;  // the next fresh matrix is one charge_reuse bought
  long bought = 0;

  bool factored = false;  // S holds a factorisation of some earlier step matrix
  bool refresh = true;    // factor the next step matrix afresh
  VectorXd v_previous;    // the velocity at the start of the previous step
  bool have_previous = false;
  // The step as a minimisation: on when asked and the system has a potential (run() decides).
  bool line_search = false;
  // Variational damping (line search in a scene with damping, run() decides): per step the
  // damping matrix Dn = -df/dv at the step's start (q_n, v_n; time t_n+1; elements projected
  // only with project_hessian: projecting every element's Hessian per step made the 13.2K-tet
  // pinned cube 4.4 times slower), and fd0, the damping force of the driven nodes' motion there, are frozen; the
  // system's own damping is off, and the step's forces are f(q) - Dn (q - q_n) / h + fd0: the
  // gradient of Phi + (q - q_n)^T Dn (q - q_n) / (2 h) - fd0 . (q - q_n), exact for the merit.
  bool variational = false;
  std::vector<double> Dn;
  VectorXd fd0;
  // ISOCHOR_TRACE_NEWTON=T: one line per Newton iteration of every step ending after time T, on
  // stderr (docs/scenes.md, diagnosing a step that fails).
  const double trace_from = std::getenv("ISOCHOR_TRACE_NEWTON") ? std::atof(std::getenv("ISOCHOR_TRACE_NEWTON"))
                                                                : std::numeric_limits<double>::infinity();
  VectorXd nu;  // the l1 merit's weights, per constraint (grow within a step)

  // One step from (qn, vn) at t to t1: q, v, lambda on return. False with a reason on failure.
  // Newton with the step matrix factored only when needed: a factorisation is reused across
  // iterations and steps while the iterations contract well (rate below 1/4); a slow or failing
  // iteration refreshes it, and a step that fails with a reused factorisation is redone with
  // fresh ones. The semi-implicit variant takes exactly one iteration with a fresh matrix.
  bool step(double t, double t1, const VectorXd& qn, const VectorXd& vn, VectorXd& q, VectorXd& v, VectorXd& lambda,
            std::string& reason) {
    const VectorXd lambda0 = lambda;
    const double h = t1 - t;
    bool ok = step_once(t1, h, qn, vn, q, v, lambda, reason, false);
    if (!ok && !opt.semi_implicit) {
      lambda = lambda0;
      refresh = true;
      have_previous = false;
      ok = step_once(t1, h, qn, vn, q, v, lambda, reason, true);
    }
    v_previous = vn;
    have_previous = true;
    return ok;
  }

  // A step that fails is retried as two half steps, each of which may be halved again, up to
  // opt.substeps_on_failure levels.
  bool advance(double t, double t1, const VectorXd& qn, const VectorXd& vn, VectorXd& q, VectorXd& v, VectorXd& lambda,
               std::string& reason, int depth = 0) {
    const VectorXd lambda0 = lambda;
    if (step(t, t1, qn, vn, q, v, lambda, reason)) return true;
    if (depth >= opt.substeps_on_failure) {
      if (depth > 0)
        reason += " (also with the step halved " +
                  (depth == 1 ? std::string("once") : std::to_string(depth) + " times") + ")";
      return false;
    }
    stats.step_halvings++;
    lambda = lambda0;
    have_previous = false;
    VectorXd qm, vm;
    const double tm = 0.5 * (t + t1);
    return advance(t, tm, qn, vn, qm, vm, lambda, reason, depth + 1) &&
           advance(tm, t1, qm, vm, q, v, lambda, reason, depth + 1);
  }

  // The incremental potential Phi at x with V = V(x) (backward_euler.hpp): inertia, potential,
  // and with variational damping the frozen damping's share.
  double phi(double h, double V, const VectorXd& x, const VectorXd& qn, const VectorXd& qt) const {
    double p = 0.5 * (x - qt).cwiseAbs2().dot(sys.mass()) / (h * h) + V;
    if (variational) {
      const VectorXd u = x - qn;
      p += 0.5 * u.dot(damping_times(u)) / h - fd0.dot(u);
    }
    return p;
  }
  VectorXd damping_times(const VectorXd& u) const {
    VectorXd y = VectorXd::Zero(n);
    sys.pattern().add_product(Dn.data(), u.data(), 1.0, y.data());
    return y;
  }
  // Phi + sum_j w_j |g_j| at x, infinite where V is not defined there; V(x) and g(x) on return.
  double merit_at(double t1, double h, const VectorXd& x, const VectorXd& qn, const VectorXd& qt, const VectorXd& w,
                  double& V, VectorXd& gx) {
    V = std::numeric_limits<double>::quiet_NaN();
    if (!sys.potential(t1, x, V) || !std::isfinite(V)) return std::numeric_limits<double>::infinity();
    if (m) sys.constraint(t1, x, gx);
    return phi(h, V, x, qn, qt) + (m ? w.dot(gx.cwiseAbs()) : 0.0);
  }
  double l1(const VectorXd& g) const { return m ? nu.dot(g.cwiseAbs()) : 0.0; }

  // Newton's convergence test, as IDA's: with the contraction rate r of the iterations since the
  // last factorisation (r^m = |dq_m| / |dq_0|), the error left after iteration m is about
  // r / (1 - r) |dq_m|; Newton stops once that is below the tolerance, newton_tol times the step's
  // displacement |q - q_n|_inf (so that the velocity (q - q_n) / h is as accurate at every h)
  // plus newton_atol. ss = r / (1 - r) is measured on the current matrix within the step (a first
  // update has none: see the test after the update); a reused matrix with r > 0.9 fails the
  // attempt (step() redoes it with fresh matrices). An iteration whose update the line search cut
  // is never the last, and the next one factors afresh.
  double ss = 20.0;

  // Restore the system's switches when a step returns (or throws): damping forces back on after
  // variational damping froze them, the projected Hessian back on after "hybrid" switched it off.
  struct DampingOff {
    ConstrainedSystem* sys = nullptr;
    ~DampingOff() {
      if (sys) sys->set_damping_forces(true);
    }
  };
  struct ProjectionOn {
    ConstrainedSystem* sys = nullptr;
    ~ProjectionOn() {
      if (sys) sys->set_hessian_projection(true);
    }
  };
  // A step's working vectors: forces, the residual's blocks (R1 dynamic rows, R0 the incremental
  // potential's gradient, R2 = g the constraints), the Newton direction and the line search's
  // trial point; kept across steps.
  struct Work {
    VectorXd f, R1, R0, R2, g, dq, dl, rhs, qtrial, gtrial, kr;
  } work;
  // Newton's verdict after an update: iterate on, converged, converged if the step's residual at
  // the new q confirms it (checked at the next iteration), or the attempt failed.
  enum class NewtonTest { go_on, done, check_residual, failed };
  // What one step's Newton iterations carry from one to the next.
  struct NewtonState {
    double first = 0;                                      // |dq| of the first iteration since the last factorisation
    int since = 0;                                         // iterations since then
    bool fresh_this_step = false;                          // a factorisation of this step's matrix
    int newton_since_fresh = 0;                            // Newton iterations since this step's last factorisation
    int whole_in_a_row = 0;                                // updates taken whole in a row (hybrid)
    bool exact_now = false;                                // hybrid: switched to the exact Hessian
    double Vq = std::numeric_limits<double>::quiet_NaN();  // V(q), when known
  };

  bool step_once(double t1, double h, const VectorXd& qn, const VectorXd& vn, VectorXd& q, VectorXd& v,
                 VectorXd& lambda, std::string& reason, bool always_fresh) {
    const VectorXd qt = qn + h * vn;  // where inertia alone would carry the nodes
    DampingOff damping_off;
    ProjectionOn projection_on;  // hybrid: each step starts projected and may switch to exact
    if (opt.exact_near_solution) projection_on.sys = &sys;
    if (variational) freeze_damping(t1, qn, vn, damping_off);
    predict(t1, h, qn, vn, qt, lambda, q);
    Work& w = work;
    const int iterations = opt.semi_implicit ? 1 : opt.max_newton;
    NewtonState ns;
    const long newton_before = stats.newton_iterations, cg_before = linear_iterations();
    if (line_search) nu.setZero(m);
    // Newton's tolerance on q at the current iterate; the step's end once converged.
    auto tolerance = [&]() { return opt.newton_tol * (q - qn).cwiseAbs().maxCoeff() + opt.newton_atol; };
    auto converged = [&]() {
      v = (q - qn) / h;
      charge_reuse(static_cast<int>(stats.newton_iterations - newton_before), ns.newton_since_fresh, ns.fresh_this_step,
                   linear_iterations() - cg_before);
      return true;
    };
    bool verify = false;  // the last update was within the tolerance: check the residual here
    for (int it = 0; it < iterations; ++it) {
      const auto ta = Clock::now();
      v = (q - qn) / h;
      const bool fresh = always_fresh || refresh || !factored || opt.semi_implicit || !opt.reuse_matrices;
      // Forces with their Jacobians for a fresh matrix; a residual check that passes needs none,
      // so they are evaluated after it.
      step_residual(t1, h, q, v, qn, qt, lambda, fresh && !verify);
      if (verify) {
        verify = false;
        if (w.R1.allFinite() && residual_error(h, w.R1, w.g) <= tolerance()) {
          stats.assembly_seconds += seconds_since(ta);
          return converged();
        }
        if (fresh) step_residual(t1, h, q, v, qn, qt, lambda, true);
      }
      if (!w.R1.allFinite()) {
        if (it == 0 && line_search && q != qn) {
          // The predictor landed where the forces are not defined (UNH beyond J = 0): start from
          // q_n instead, where the last step left every force finite.
          q = qn;
          --it;
          continue;
        }
        reason = "the forces are not finite (an element inverted or exploded)";
        return false;
      }
      if (fresh) assemble_step_matrix(t1, h, q, lambda);
      stats.assembly_seconds += seconds_since(ta);
      double shift = 0.0, slope = 0.0;
      const Direction direction = newton_direction(fresh, h, lambda, shift, slope, ns, reason);
      if (direction == Direction::failed) return false;
      if (direction == Direction::redo) continue;
      double alpha = 1.0;
      const double size = w.dq.cwiseAbs().maxCoeff();
      const double tol = tolerance();
      const Search found = line_search_step(t1, h, q, qn, qt, fresh, slope, size, tol, ns, alpha, reason);
      if (found == Search::retry_fresh) continue;
      if (found == Search::failed) return false;
      if (trace_from <= t1)
        std::fprintf(stderr, "newton t=%.9g it=%d fresh=%d shift=%g |dq|=%.3e tol=%.3e alpha=%g slope=%.3e |R|=%.3e\n",
                     t1, it, static_cast<int>(fresh), shift, size, tol, alpha, slope, w.R1.norm());
      if (!take_update(alpha, q, lambda, ns)) {
        reason = "Newton produced a non-finite state";
        return false;
      }
      if (opt.semi_implicit) break;
      const NewtonTest test = after_update(fresh, it, alpha, size, tol, lambda, ns, reason);
      if (test == NewtonTest::failed) return false;
      if (test == NewtonTest::done) return converged();
      verify = test == NewtonTest::check_residual;
    }
    v = (q - qn) / h;
    if (opt.semi_implicit) return true;
    reason = "Newton did not converge in " + std::to_string(opt.max_newton) + " iterations";
    stats.newton_failures++;
    return false;
  }

  // q and lambda moved by alpha (work.dq, work.dl), counted as a Newton iteration; false where q
  // is no longer finite.
  bool take_update(double alpha, VectorXd& q, VectorXd& lambda, NewtonState& ns) {
    q += alpha * work.dq;
    if (m) lambda += alpha * work.dl;
    stats.newton_iterations++;
    ns.newton_since_fresh++;
    return q.allFinite();
  }

  // After an update of length alpha along work.dq (|dq| = size, at tolerance tol): hybrid's
  // switch to the exact Hessian after two whole updates in a row; for a whole update, the
  // contraction rate of the current matrix (from its first update in this step on: slow, a fresh
  // matrix for the next step; a reused one that no longer contracts fails the attempt, and step()
  // redoes it with fresh ones) and Newton's test. A cut update is never the last.
  NewtonTest after_update(bool fresh, int it, double alpha, double size, double tol, const VectorXd& lambda,
                          NewtonState& ns, std::string& reason) {
    ns.whole_in_a_row = alpha < 1.0 ? 0 : ns.whole_in_a_row + 1;
    if (opt.exact_near_solution && line_search && ns.whole_in_a_row == 2 && !ns.exact_now) {
      sys.set_hessian_projection(false);  // near the solution: the exact Hessian from here on
      ns.exact_now = true;
      refresh = true;
    }
    if (alpha < 1.0) return NewtonTest::go_on;  // the next iteration factors afresh
    if (fresh || it == 0) {                     // the rate is measured from the last factorisation on
      ns.first = size;
      ns.since = 0;
    } else {
      const double rate = std::pow(size / ns.first, 1.0 / ++ns.since);
      if (rate > 0.25) refresh = true;  // slow contraction: a fresh matrix for the next step
      if (rate > 0.9 && !ns.fresh_this_step) {
        reason = "Newton stalled with a reused matrix (contraction rate " + std::to_string(rate) + ")";
        return NewtonTest::failed;
      }
      ss = rate < 0.9 ? rate / (1.0 - rate) : 1e300;  // no estimate yet: iterate on
    }
    return newton_test(ns.since, size, tol, m ? work.dl.cwiseAbs().maxCoeff() : 0.0, lambda);
  }

  // Variational damping: Dn and fd0 frozen at the step's start (q_n, v_n: the same whatever the
  // predictor, so a resumed run repeats the steps), before the predictor's merit needs them; the
  // system's damping stays off until the step returns (`off` turns it back on).
  void freeze_damping(double t1, const VectorXd& qn, const VectorXd& vn, DampingOff& off) {
    sys.set_damping_forces(true);
    std::fill(Dn.begin(), Dn.end(), 0.0);
    sys.add_force_jacobians(t1, qn, vn, nullptr, Dn.data());
    const VectorXd still = VectorXd::Zero(n);
    VectorXd fa, fb;
    sys.force(t1, qn, still, fa);
    sys.set_damping_forces(false);
    off.sys = &sys;
    sys.force(t1, qn, still, fb);
    fd0 = fa - fb;
  }

  // The predictor: the velocity extrapolated linearly from the last two steps (the first step and
  // the semi-implicit variant, whose single iteration starts from it, use q_n + h v_n). With the
  // line search, the extrapolation is kept only where its merit (the multipliers of the last step
  // weighing the constraints) is below that of q_n + h v_n: at large steps in an oscillating body
  // the extrapolated velocity can overshoot by far.
  void predict(double t1, double h, const VectorXd& qn, const VectorXd& vn, const VectorXd& qt, const VectorXd& lambda,
               VectorXd& q) {
    if (have_previous && !opt.semi_implicit)
      q = qn + h * (2 * vn - v_previous);
    else
      q = qt;
    if (line_search && have_previous && !opt.semi_implicit) {
      const VectorXd w = 2.0 * lambda.cwiseAbs();
      double V;
      VectorXd gx(m);
      if (!(merit_at(t1, h, q, qn, qt, w, V, gx) <= merit_at(t1, h, qt, qn, qt, w, V, gx))) q = qt;
    }
  }

  // The step's residual at (q, v) into work: the forces (with their Jacobians into K and D when
  // asked), R1 = M (q - q~) / h^2 - f (+ the frozen damping) + G^T lambda, R0 without the
  // constraint forces (the incremental potential's gradient, for the line search), R2 = g.
  void step_residual(double t1, double h, const VectorXd& q, const VectorXd& v, const VectorXd& qn, const VectorXd& qt,
                     const VectorXd& lambda, bool jacobians) {
    Work& w = work;
    if (jacobians) {
      std::fill(K.begin(), K.end(), 0.0);
      std::fill(D.begin(), D.end(), 0.0);
    }
    sys.force_and_jacobians(t1, q, v, w.f, jacobians ? K.data() : nullptr, jacobians ? D.data() : nullptr);
    w.R1 = sys.mass().cwiseProduct(q - qt) / (h * h) - w.f;
    if (variational) w.R1 += damping_times(q - qn) / h - fd0;
    if (line_search) w.R0 = w.R1;
    add_constraint_terms(sys, t1, q, lambda, G, w.g, w.R1.data());
    if (m) w.R2 = w.g;
  }

  // The step matrix Sv = M / h^2 + K + sum_j lambda_j H_j + D / h (Dn with variational damping)
  // from the Jacobians step_residual() assembled.
  void assemble_step_matrix(double t1, double h, const VectorXd& q, const VectorXd& lambda) {
    if (m) sys.add_constraint_hessian(t1, q, lambda, 1.0, K.data());
    const std::vector<double>& Dm = variational ? Dn : D;
    for (std::size_t k = 0; k < Sv.size(); ++k) Sv[k] = K[k] + Dm[k] / h;
    const VectorXd& M = sys.mass();
    for (Index i = 0; i < n; ++i) Sv[diag[i]] += M[i] / (h * h);
  }

  // Newton's direction (work.dq, work.dl): the step matrix factored (when fresh) and solved; with
  // the line search, a matrix that cannot be factored or a direction that does not descend is
  // shifted by more inertia (shift M / h^2), and a reused matrix that gives no descent asks for a
  // fresh one (redo). slope: the l1 merit's slope along dq (line search only).
  enum class Direction { ok, redo, failed };
  Direction newton_direction(bool fresh, double h, const VectorXd& lambda, double& shift, double& slope,
                             NewtonState& ns, std::string& reason) {
    Work& w = work;
    for (;;) {
      if (fresh) {
        const auto tf = Clock::now();
        bool ok;
        if (use_kkt) {
          layout->fill(Sv.data(), G, kv.data());
          ok = kkt->factor(kv.data());
        } else {
          ok = S->factor(Sv.data());
          stats.symbolic_seconds = analyse_seconds();
        }
        stats.factor_seconds += seconds_since(tf);
        stats.jacobian_evals++;
        stats.fresh_factorisations++;
        factored = ok;
        refresh = false;
        ns.fresh_this_step = true;
        ns.newton_since_fresh = 0;
        if (buying) bought++;
        buying = false;
        ss = 20.0;
        if (!ok) {
          if (line_search && add_shift(shift, h)) continue;
          reason = "the step matrix is singular";
          return Direction::failed;
        }
      }
      const auto ts = Clock::now();
      bool solved = true;
      if (use_kkt) {
        w.kr << -w.R1, -w.R2;
        kkt->solve(w.kr.data());
        w.dq = w.kr.head(n);
        w.dl = w.kr.tail(m);
        solved = w.kr.allFinite();
      } else {
        // The current borders with the (possibly reused) factor of the step matrix.
        w.dq.resize(n);
        w.dl.resize(m);
        w.rhs = -w.R1;
        const VectorXd r2 = -w.R2;
        solved = S->set_borders(G);
        solved = S->solve(w.rhs.data(), r2.data(), w.dq.data(), w.dl.data()) && solved;
        stats.linear_iterations = linear_iterations();
      }
      stats.solve_seconds += seconds_since(ts);
      if (!solved && !line_search) {
        reason = "the linear solve failed (PCG did not converge, or the step matrix is indefinite)";
        return Direction::failed;
      }
      if (!line_search) return Direction::ok;
      if (solved) {
        // The l1 merit's weights exceed the new multipliers, so that a Newton direction of a
        // positive definite matrix descends; its slope along dq.
        for (Index j = 0; j < m; ++j) nu[j] = std::max(nu[j], 2.0 * std::abs(lambda[j] + w.dl[j]));
        slope = w.R0.dot(w.dq) - l1(w.g);
        if (slope < 0) return Direction::ok;
      }
      if (!fresh) {  // a reused matrix: try a fresh one before shifting
        refresh = true;
        return Direction::redo;
      }
      if (!add_shift(shift, h)) {
        reason = solved ? "Newton's direction does not descend the merit function even with the inertia scaled by 1e6"
                        : "the linear solve failed (PCG did not converge, or the step matrix is indefinite)";
        return Direction::failed;
      }
    }
  }

  // Backtracking (Armijo, halving) on the step's merit along work.dq from q; rounding in its value
  // is allowed. alpha: the length taken. A search that fails with a reused matrix is redone with a
  // fresh one (retry_fresh); a cut search asks for a fresh matrix at the next iteration. Vq: V(q)
  // when known, V at the point taken on return.
  enum class Search { taken, retry_fresh, failed };
  Search search_along(double t1, double h, const VectorXd& q, const VectorXd& qn, const VectorXd& qt, bool fresh,
                      double slope, double& Vq, double& alpha) {
    Work& w = work;
    if (!std::isfinite(Vq) && !sys.potential(t1, q, Vq)) Vq = std::numeric_limits<double>::infinity();
    const double phi_q = phi(h, Vq, q, qn, qt);
    const double merit0 = phi_q + l1(w.g);
    const double noise = 1e-13 * (std::abs(phi_q) + std::abs(Vq) + l1(w.g));
    bool found = false;
    for (; alpha >= 1e-10; alpha *= 0.5) {
      w.qtrial = q + alpha * w.dq;
      double Vt;
      const double merit = merit_at(t1, h, w.qtrial, qn, qt, nu, Vt, w.gtrial);
      if (std::isfinite(merit) && merit <= merit0 + 1e-4 * alpha * slope + noise) {
        Vq = Vt;
        if (opt.on_line_search) opt.on_line_search(merit0, merit, alpha);
        found = true;
        break;
      }
    }
    if (!found) {
      if (fresh) return Search::failed;
      refresh = true;
      Vq = std::numeric_limits<double>::quiet_NaN();
      return Search::retry_fresh;
    }
    if (alpha < 1.0) {
      stats.line_search_cuts++;
      refresh = true;
    }
    return Search::taken;
  }

  // The step length alpha along Newton's direction: the line search's where the update is large
  // against the tolerance, else the whole update (the merit V(q) is then not known).
  Search line_search_step(double t1, double h, const VectorXd& q, const VectorXd& qn, const VectorXd& qt, bool fresh,
                          double slope, double size, double tol, NewtonState& ns, double& alpha, std::string& reason) {
    if (!line_search || size <= 100.0 * tol) {
      ns.Vq = std::numeric_limits<double>::quiet_NaN();
      return Search::taken;
    }
    const Search found = search_along(t1, h, q, qn, qt, fresh, slope, ns.Vq, alpha);
    if (found == Search::failed)
      reason = "the line search found no decrease of the merit function along Newton's direction";
    return found;
  }

  // Whether ss, measured on the current matrix in an earlier step, bounds this step's first
  // update: a rate was measured (ss < 20, reset at each factorisation) and the factor does not
  // hold the constraint rows (KLU's KKT matrix keeps G from its factorisation, and G turns with
  // the body: on the pendulum its carried rate left the multipliers 1e-3 off and the end 0.2
  // digit behind; the Schur complement is formed with the current G).
  bool rate_carries() const { return ss < 20.0 && (!use_kkt || m == 0); }

  // Newton's test after a whole update of size `size` in q and `lsize` in the multipliers, `since`
  // updates after the first on the current matrix. With a rate measured on this matrix within the
  // step: done when ss |dq| <= tol. A first update has no rate of its own; one carried from
  // earlier steps counts only where rate_carries() (trusted on KLU's KKT matrix it left the
  // MEBDFDAE pendulum 0.27 digit less accurate at h = 1e-4, docs/results/tolerance.md). So a first
  // update counts only when the multipliers moved by little too (newton_tol of the larger of
  // their size and the system's force scale; the residual check is blind to them at small h,
  // h^2 G^T dlambda / M), both scaled by the carried rate where it carries, else as they are,
  // and then only once the step's residual at the new q confirms it (residual_error, checked at
  // the next iteration's residual, without a solve), unless the update is tiny against the
  // tolerance. Once a rate is measured, the positions decide: the multipliers' change near
  // rounding has no rate to measure.
  NewtonTest newton_test(int since, double size, double tol, double lsize, const VectorXd& lambda) const {
    if (since > 0) return ss * size <= tol ? NewtonTest::done : NewtonTest::go_on;
    const double ltol = m ? opt.newton_tol * std::max(lambda.cwiseAbs().maxCoeff(), sys.force_scale()) : 0.0;
    if (rate_carries() && ss * size <= tol && ss * lsize <= ltol) return NewtonTest::check_residual;
    if (size > tol || lsize > ltol) return NewtonTest::go_on;
    return size <= 1e-4 * tol ? NewtonTest::done : NewtonTest::check_residual;
  }

  // An upper estimate of the distance from q to the step's solution, from the residual alone:
  // the dynamic rows' residual r moves q by S^-1 r, whose M-norm is at most h^2 |r|_M^-1 for a
  // positive semi-definite K (S >= M / h^2), taken per dof as h^2 |r_i| / M_i; a constraint's
  // residual g_j is a distance |g_j| / |G_j| from its surface.
  double residual_error(double h, const VectorXd& R1, const VectorXd& g) const {
    const VectorXd& M = sys.mass();
    double e = 0;
    for (Index i = 0; i < n; ++i) e = std::max(e, h * h * std::abs(R1[i]) / M[i]);
    for (Index j = 0; j < m; ++j) {
      double norm = 0;
      for (double x : G[j]) norm += x * x;
      e = std::max(e, std::abs(g[j]) / std::max(std::sqrt(norm), 1e-300));
    }
    return e;
  }

  // Adds inertia to the step matrix Sv: shift (a multiple of M / h^2 on top of the one there)
  // goes 0 -> 1 -> 10 -> ... -> 1e6. False once it is used up.
  bool add_shift(double& shift, double h) {
    const double next = shift == 0.0 ? 1.0 : 10.0 * shift;
    if (next > 1e6) return false;
    const VectorXd& M = sys.mass();
    for (Index i = 0; i < n; ++i) Sv[diag[i]] += (next - shift) * M[i] / (h * h);
    shift = next;
    stats.regularisations++;
    return true;
  }
};

BackwardEuler::BackwardEuler(ConstrainedSystem& system, BackwardEulerOptions options)
    : impl_(std::make_unique<Impl>(system, options)) {}
BackwardEuler::~BackwardEuler() = default;

RunStats BackwardEuler::run(const std::vector<double>& times, const FrameCallback& on_frame) {
  begin(times, on_frame);
  step(times.back());
  return finish();
}

void BackwardEuler::begin(const std::vector<double>& times, const FrameCallback& on_frame) {
  Impl& s = *impl_;
  const double h = s.opt.dt;
  VectorXd q, v, a, lambda;
  consistent_initial_state(s.sys, times.front(), q, v, a, lambda);
  double V0;
  // The line search needs a potential, and where the scene damps, the switch that freezes the
  // damping per step (without it: plain Newton).
  s.line_search = s.opt.line_search && !s.opt.semi_implicit && s.sys.potential(times.front(), q, V0) &&
                  (!s.sys.has_damping() || s.sys.set_damping_forces(true));
  s.variational = s.line_search && s.sys.has_damping();
  // With the line search an indefinite step matrix is shifted (step_once), never factored as it
  // is: CHOLMOD's LDL^T of it gave directions the search cut to 1/8-1/128, and the 4.7K-tet ball
  // at 1 ms failed at 36 ms where PCG, which stops on such a matrix, ran through.
  s.refuse_indefinite = s.line_search;
  if (!s.use_kkt) {
    LinearSolverKind kind = s.opt.linear_solver;
    // On P ranks "auto" is PCG throughout: it is the solver whose work the ranks split.
    const bool ranks = s.sys.partition() != nullptr;
    if (s.opt.automatic_linear_solver)
      kind = ranks || (s.line_search && s.n >= BackwardEulerOptions::kAutoKrylovMinDofs) ? LinearSolverKind::krylov
                                                                                         : LinearSolverKind::reduced;
    s.make_step_solver(kind);
    s.choosing = s.opt.automatic_linear_solver && s.line_search && !ranks;
  }
  if (s.variational) s.Dn.assign(s.sys.pattern().nnz(), 0.0);
  auto step = [&s](double t, double t1, const VectorXd& qn, const VectorXd& vn, VectorXd& q1, VectorXd& v1,
                   VectorXd& l1, std::string& reason) {
    const Impl::StepCounts before = s.counts();
    if (!s.advance(t, t1, qn, vn, q1, v1, l1, reason)) return false;
    if (s.choosing) s.after_step(before);
    if (s.opt.rescale_volume && !s.sys.rescale_volume(t1, q1)) {
      reason = "this model has no volume rescaling";
      return false;
    }
    return true;
  };
  auto sample = [&s, h]() {
    return RunStats::FrameSample{
        s.stats.steps, s.stats.newton_iterations, 0, s.stats.newton_failures, s.stats.jacobian_evals, 1, h};
  };
  // Frames between steps: the interpolation projected back onto the constraints (as IDA's frames).
  FrameCorrection between;
  if (s.m > 0)
    between = [&s](double t, VectorXd& qf, VectorXd& vf) {
      const auto tp = Clock::now();
      project_state(s.sys, t, qf, vf);
      s.stats.projection_seconds += seconds_since(tp);
    };
  s.stepper = std::make_unique<FixedStepper>(times, h, s.opt.max_steps, step, s.stats, sample, on_frame, between);
  s.stepper->begin(q, v, lambda);
}

double BackwardEuler::step(double t_out) {
  if (!impl_->stepper) throw Error("BackwardEuler::step before begin");
  return impl_->stepper->step(t_out);
}

RunStats BackwardEuler::finish() {
  impl_->stepper.reset();
  return impl_->stats;
}

}  // namespace isochor
