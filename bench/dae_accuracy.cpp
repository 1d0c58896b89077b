// Accuracy of every IDA linear solver and of backward Euler on the two index-3 test DAEs
// (tests/dae_problems.hpp): significant correct digits of the positions and velocities at the
// end time against the published references, steps, Newton iterations and CPU time, one CSV row
// per run on stdout. bench/dae_accuracy.sh runs it and draws docs/results/tolerance/.
//
//   isochor_bench_dae [ida|be|all]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "../tests/dae_problems.hpp"
#include "isochor/backward_euler.hpp"
#include "isochor/ida_integrator.hpp"

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
  double digits = 0, lambda_digits = 0, trajectory_digits = 0, cpu = 0;
  RunStats stats;
  bool ok = true;
};

constexpr double kFrame = 0.01;  // frames every 10 ms, compared along the run

template <class MakeIntegrator>
Outcome run(test::TestDae& dae, MakeIntegrator make) {
  Outcome o;
  std::vector<double> times;
  for (int k = 0; k * kFrame <= dae.end_time() + 1e-12; ++k) times.push_back(k * kFrame);
  times.back() = dae.end_time();
  std::vector<VectorXd> qr, vr;
  dae.reference_trajectory(times, 2e-5, qr, vr);
  const auto c0 = std::clock();
  try {
    auto integ = make(dae);
    std::vector<VectorXd> qs, vs;
    VectorXd l;
    o.stats = integ->run(times, [&](int, double, const VectorXd& qf, const VectorXd& vf, const VectorXd& lf,
                                    const RunStats::FrameSample&) {
      qs.push_back(qf);
      vs.push_back(vf);
      l = lf;
    });
    o.digits = dae.correct_digits(qs.back(), vs.back());
    o.lambda_digits = dae.multiplier_digits(l);
    o.trajectory_digits = test::TestDae::trajectory_digits(qs, vs, qr, vr);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "failed: %s\n", e.what());
    o.ok = false;
  }
  o.cpu = static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
  return o;
}

void print(const char* problem, const char* method, const char* solver, double tol, const Outcome& o) {
  std::printf("%s,%s,%s,%.3g,%d,%.4f,%.4f,%.4f,%ld,%ld,%ld,%ld,%ld,%.6f\n", problem, method, solver, tol, o.ok ? 1 : 0,
              o.digits, o.trajectory_digits, o.lambda_digits, o.stats.steps, o.stats.newton_iterations,
              o.stats.newton_failures, o.stats.error_test_failures, o.stats.fresh_factorisations, o.cpu);
}

}  // namespace

int main(int argc, char** argv) {
  const std::string what = argc > 1 ? argv[1] : "all";
  const Solver solvers[] = {{"klu_metis", LinearSolverKind::klu, KluOrdering::metis},
                            {"klu_colamd", LinearSolverKind::klu, KluOrdering::colamd},
                            {"klu_amd", LinearSolverKind::klu, KluOrdering::amd},
                            {"reduced", LinearSolverKind::reduced, KluOrdering::metis},
                            {"krylov", LinearSolverKind::krylov, KluOrdering::metis}};
  std::printf("problem,method,solver,tol,ok,digits,trajectory_digits,lambda_digits,steps,newton,newton_failures,error_test_failures,factorisations,cpu_s\n");
  for (const char* problem : {"pendulum", "caraxis"}) {
    if (what == "all" || what == "ida")
      for (const Solver& s : solvers)
        for (double rtol : {1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10}) {
          auto dae = make_problem(problem);
          const Outcome o = run(*dae, [&](test::TestDae& d) {
            IdaOptions opt;
            opt.rtol = opt.atol_q = opt.atol_v = rtol;
            opt.linear_solver = s.kind;
            opt.ordering = s.ordering;
            if (std::getenv("DAE_NEWTON_COEF")) opt.newton_coef = std::atof(std::getenv("DAE_NEWTON_COEF"));
            return std::make_unique<IdaIntegrator>(d, opt);
          });
          print(problem, "ida", s.name, rtol, o);
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
