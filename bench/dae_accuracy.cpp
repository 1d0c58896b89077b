// Accuracy of every IDA linear solver and of backward Euler on the two index-3 test DAEs
// (tests/dae_problems.hpp): correct digits of the positions and velocities at the end time
// against the published references and along the run against the Runge-Kutta reference, the
// multipliers' digits at the end, steps, Newton iterations and failures, and CPU time, one CSV
// row per run on stdout. bench/dae_accuracy.sh runs it and draws docs/results/tolerance/.
// DAE_NEWTON_COEF (IDA's integrator.newton_coef) and DAE_NEWTON_TOL (backward Euler's
// integrator.newton_tol), when set, replace the defaults for every run.
//
//   isochor_bench_dae [ida|band|be|all]
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "../tests/dae_problems.hpp"
#include "isochor/integrators/backward_euler.hpp"
#include "isochor/integrators/ida_integrator.hpp"
#include "isochor/integrators/sparse_factor.hpp"

using namespace isochor;

namespace {

struct Solver {
  const char* name;
  LinearSolverKind kind;
  KluOrdering ordering;
};

std::unique_ptr<test::TestDae> make_problem(const std::string& name) {
  if (name == "pendulum") return std::make_unique<test::MebdfPendulum>();
  return std::make_unique<test::CarAxis>();
}

struct Outcome {
  test::DaeRun run;
  double cpu = 0;
  bool ok = true;
};

template <class MakeIntegrator>
Outcome run(test::TestDae& dae, MakeIntegrator make) {
  Outcome o;
  std::vector<VectorXd> qr, vr;
  dae.reference_trajectory(test::dae_frames(dae.end_time()), 2e-5, qr, vr);
  const auto c0 = std::clock();
  try {
    auto integ = make(dae);
    o.run = test::run_dae(dae, *integ, qr, vr);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "failed: %s\n", e.what());
    o.ok = false;
  }
  o.cpu = static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
  return o;
}

void print(const char* problem, const char* method, const char* solver, double tol, const Outcome& o) {
  std::printf("%s,%s,%s,%.3g,%d,%.4f,%.4f,%.4f,%ld,%ld,%ld,%ld,%ld,%.6f\n", problem, method, solver, tol, o.ok ? 1 : 0,
              o.run.end_digits, o.run.trajectory_digits, o.run.lambda_digits, o.run.stats.steps,
              o.run.stats.newton_iterations, o.run.stats.newton_failures, o.run.stats.error_test_failures,
              o.run.stats.fresh_factorisations, o.cpu);
}

// One IDA run of `problem` with solver s at rtol = atol_q = atol_v = rtol.
Outcome run_ida(const char* problem, const Solver& s, double rtol) {
  auto dae = make_problem(problem);
  return run(*dae, [&](test::TestDae& d) {
    IdaOptions opt;
    opt.rtol = opt.atol_q = opt.atol_v = rtol;
    opt.linear_solver = s.kind;
    opt.ordering = s.ordering;
    if (std::getenv("DAE_NEWTON_COEF")) opt.newton_coef = std::atof(std::getenv("DAE_NEWTON_COEF"));
    return std::make_unique<IdaIntegrator>(d, opt);
  });
}

}  // namespace

int main(int argc, char** argv) {
  const std::string what = argc > 1 ? argv[1] : "all";
  if (what != "all" && what != "ida" && what != "band" && what != "be") {
    std::fprintf(stderr, "usage: isochor_bench_dae [ida|band|be|all]\n");
    return 2;
  }
  const Solver solvers[] = {{"klu_metis", LinearSolverKind::klu, KluOrdering::metis},
                            {"klu_colamd", LinearSolverKind::klu, KluOrdering::colamd},
                            {"klu_amd", LinearSolverKind::klu, KluOrdering::amd},
                            {"reduced", LinearSolverKind::reduced, KluOrdering::metis},
                            {"krylov", LinearSolverKind::krylov, KluOrdering::metis},
                            {"amg", LinearSolverKind::amg, KluOrdering::metis}};
  std::printf(
      "problem,method,solver,tol,ok,digits,trajectory_digits,lambda_digits,steps,newton,newton_failures,error_test_"
      "failures,factorisations,cpu_s\n");
  for (const char* problem : {"pendulum", "caraxis"}) {
    if (what == "all" || what == "ida")
      for (const Solver& s : solvers) {
        if (s.kind == LinearSolverKind::amg && !amg_available()) continue;
        for (double rtol : {1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10})
          print(problem, "ida", s.name, rtol, run_ida(problem, s, rtol));
      }
    // The band: nine tolerances within 4% of each decade (method ida_band), to separate what a
    // solver changes from how much one solver's error moves with the tolerance alone.
    if (what == "all" || what == "band")
      for (const Solver& s : solvers) {
        if (s.kind == LinearSolverKind::amg && !amg_available()) continue;
        for (double rtol : {1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10})
          for (int k = -4; k <= 4; ++k) {
            const double r = rtol * (1 + 0.01 * k);
            print(problem, "ida_band", s.name, r, run_ida(problem, s, r));
          }
      }
    if (what == "all" || what == "be")
      for (const char* solver : {"reduced", "klu", "klu_exact"})
        for (double h : {1e-3, 1e-4, 1e-5}) {
          auto dae = make_problem(problem);
          const Outcome o = run(*dae, [&](test::TestDae& d) {
            BackwardEulerOptions opt;
            opt.dt = h;
            opt.linear_solver = std::strcmp(solver, "reduced") == 0 ? LinearSolverKind::reduced : LinearSolverKind::klu;
            opt.reuse_matrices = std::strcmp(solver, "klu_exact") != 0;
            if (std::getenv("DAE_NEWTON_TOL")) opt.newton_tol = std::atof(std::getenv("DAE_NEWTON_TOL"));
            return std::make_unique<BackwardEuler>(d, opt);
          });
          print(problem, "backward_euler", solver, h, o);
        }
  }
  return 0;
}
