#include "run.hpp"

#include <chrono>

#include "isochor/backward_euler.hpp"
#include "isochor/error.hpp"
#include "isochor/mesh_system.hpp"
#include "isochor/output.hpp"
#include "isochor/progress.hpp"
#include "isochor/statics.hpp"
#include "isochor/xpbd_system.hpp"

namespace isochor {

namespace {
void write_totals(OutputWriter& w, const IdaStats& s) {
  w.set_stat("steps", static_cast<double>(s.steps));
  w.set_stat("residual_evaluations", static_cast<double>(s.residual_evals));
  w.set_stat("jacobian_evaluations", static_cast<double>(s.jacobian_evals));
  w.set_stat("linear_setups", static_cast<double>(s.linear_setups));
  w.set_stat("newton_iterations", static_cast<double>(s.newton_iterations));
  w.set_stat("rejected_steps_newton", static_cast<double>(s.newton_failures));
  w.set_stat("rejected_steps_error_test", static_cast<double>(s.error_test_failures));
  w.set_stat("fresh_factorisations", static_cast<double>(s.fresh_factorisations));
  w.set_stat("wall_seconds", s.wall_seconds);
  w.set_stat("assembly_seconds", s.assembly_seconds);
  w.set_stat("factorisation_seconds", s.factor_seconds);
  w.set_stat("solve_seconds", s.solve_seconds);
}
}  // namespace

RunSummary run_scene(const Scene& sc, const std::string& output, bool progress) {
  const std::string& kind = sc.integrator.kind;
  if (kind != "ida" && kind != "backward_euler" && kind != "semi_implicit" && kind != "static" && kind != "xpbd")
    throw Error(sc.file.name() + ": integrator.kind = \"" + kind +
                "\" is not available yet (expected \"ida\", \"backward_euler\", \"semi_implicit\", \"static\" or \"xpbd\")");
  if ((kind == "static") != (sc.frames.count > 0))
    throw Error(sc.file.name() + (kind == "static" ? ": a static run needs frames.count (load increments)"
                                                   : ": frames.count is for statics; a dynamic run needs frames.rate and frames.duration"));
  RunSummary summary;
  summary.output = output.empty() ? sc.output.path : output;
  MeshSystem sys(sc);
  IdaOptions o;
  o.rtol = sc.integrator.rtol;
  o.atol_q = sc.integrator.atol;
  o.max_order = sc.integrator.max_order;
  o.max_step = sc.integrator.max_step;
  o.max_steps = sc.integrator.max_steps;
  o.ordering = sc.integrator.ordering;
  o.linear_solver = sc.integrator.linear_solver;
  BackwardEulerOptions be;
  be.dt = sc.integrator.dt;
  be.newton_tol = sc.integrator.newton_tol;
  be.semi_implicit = kind == "semi_implicit";
  be.max_steps = sc.integrator.max_steps;
  be.rescale_volume = sc.integrator.rescale_volume;
  XpbdOptions xo;
  xo.dt = sc.integrator.dt;
  xo.substeps = sc.integrator.substeps;
  xo.iterations = sc.integrator.iterations;
  xo.max_steps = sc.integrator.max_steps;
  OutputWriter w(summary.output, sc.mesh, sc.zones, {sc.file.text_as_run(), sc.file.name(), "run"}, sc.output.pressure);
  const std::vector<double> times = sc.frames.times();
  Progress bar(sc.file.name(), static_cast<int>(times.size()) - 1, progress ? stderr : nullptr);
  std::vector<double> pressure;
  const auto start = std::chrono::steady_clock::now();
  auto on_frame = [&](int k, double t, const VectorXd& q, const VectorXd& v, const VectorXd& lambda,
                      const IdaStats::FrameSample& s) {
    sys.set_state(t, q, v);
    Frame f;
    f.time = t;
    f.positions = &sys.positions();
    f.volumes = sys.volumes();
    f.energy = sys.energies();
    if (sc.output.pressure) {
      sys.pressures(lambda, pressure);
      f.pressure = &pressure;
    }
    f.stats = {{"inverted_tets", static_cast<double>(sys.inverted_tets())},
               {"steps", static_cast<double>(s.steps)},
               {"newton_iterations", static_cast<double>(s.newton_iterations)},
               {"jacobian_evaluations", static_cast<double>(s.jacobian_evals)},
               {"rejected_steps_error_test", static_cast<double>(s.error_test_failures)},
               {"rejected_steps_newton", static_cast<double>(s.newton_failures)},
               {"order", static_cast<double>(s.order)},
               {kind == "static" ? "residual_norm" : "step_size", s.step_size},
               {"wall_seconds", std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()}};
    w.write_frame(f);
    summary.frames = k + 1;
    if (progress) bar.update(k, t);
  };
  try {
    if (kind == "ida") summary.stats = IdaIntegrator(sys, o).run(times, on_frame);
    else if (kind == "static") summary.stats = StaticSolver(sys, StaticOptions{}).run(times, on_frame);
    else if (kind == "xpbd") {
      // XPBD works on every node; frames are written through the mesh system's free dofs.
      XpbdMeshSystem points(sc);
      const auto& free = sys.dofs().free_nodes;
      VectorXd q(sys.num_dofs()), v(sys.num_dofs());
      summary.stats = Xpbd(points, xo).run(times, [&](int k, double t, const VectorXd& x, const VectorXd& xv,
                                                        const VectorXd& lambda, const IdaStats::FrameSample& s) {
        for (std::size_t f = 0; f < free.size(); ++f) {
          q.segment<3>(3 * f) = x.segment<3>(3 * free[f]);
          v.segment<3>(3 * f) = xv.segment<3>(3 * free[f]);
        }
        on_frame(k, t, q, v, lambda, s);
      });
    }
    else summary.stats = BackwardEuler(sys, be).run(times, on_frame);
  } catch (const IntegrationError& e) {
    w.set_stat("failed_at_time", e.time);
    w.set_stat("failure", std::string(e.what()));
    w.close();
    throw Error(sc.file.name() + ": " + e.what() + "; " + std::to_string(summary.frames) + " frames saved in " +
                summary.output);
  }
  write_totals(w, summary.stats);
  w.close();
  bar.finish();
  return summary;
}

}  // namespace isochor
