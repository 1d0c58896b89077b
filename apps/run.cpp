#include "run.hpp"


#include <chrono>

#include "isochor/integrator_registry.hpp"
#include "isochor/error.hpp"
#include "isochor/memory.hpp"
#include "isochor/output.hpp"
#include "isochor/progress.hpp"
#include "isochor/scene_system.hpp"

namespace isochor {

namespace {

void write_totals(OutputWriter& w, const RunStats& s) {
  w.set_stat("steps", static_cast<double>(s.steps));
  w.set_stat("residual_evaluations", static_cast<double>(s.residual_evals));
  w.set_stat("jacobian_evaluations", static_cast<double>(s.jacobian_evals));
  w.set_stat("linear_setups", static_cast<double>(s.linear_setups));
  w.set_stat("newton_iterations", static_cast<double>(s.newton_iterations));
  w.set_stat("rejected_steps_newton", static_cast<double>(s.newton_failures));
  w.set_stat("rejected_steps_error_test", static_cast<double>(s.error_test_failures));
  w.set_stat("fresh_factorisations", static_cast<double>(s.fresh_factorisations));
  w.set_stat("reused_jacobians", static_cast<double>(s.reused_jacobians));
  w.set_stat("linear_fallbacks", static_cast<double>(s.linear_fallbacks));
  w.set_stat("wall_seconds", s.wall_seconds);
  w.set_stat("assembly_seconds", s.assembly_seconds);
  w.set_stat("factorisation_seconds", s.factor_seconds);
  w.set_stat("solve_seconds", s.solve_seconds);
  w.set_stat("factor_nnz", s.factor_nnz);
  w.set_stat("symbolic_seconds", s.symbolic_seconds);
  w.set_stat("projection_seconds", s.projection_seconds);
  w.set_stat("linear_iterations", static_cast<double>(s.linear_iterations));
  // Peak resident memory of the whole process (getrusage), for the linear-solver benchmarks.
  w.set_stat("peak_memory_mb", peak_memory_mb());
}

// Each frame of the integrator, measured by the scene system and written with its statistics.
FrameCallback frame_writer(const Scene& sc, SceneSystem& sys, OutputWriter& w, Progress& bar, RunSummary& summary,
                           bool progress) {
  const auto start = std::chrono::steady_clock::now();
  const bool tets = sys.has_tets();
  return [&, start, tets, pressure = std::vector<double>(), loads = Points()](
             int k, double t, const VectorXd& q, const VectorXd& v, const VectorXd& lambda,
             const RunStats::FrameSample& s) mutable {
    sys.set_state(t, q, v);
    Frame f;
    f.time = t;
    f.positions = &sys.positions();
    f.volumes = sys.volumes();
    f.energy = sys.energies();
    if (tets && sc.output.pressure) {
      sys.pressures(lambda, pressure);
      f.pressure = &pressure;
    }
    if (sys.has_loads()) {
      sys.loads(loads);
      f.loads = &loads;
    }
    if (tets) f.stats.push_back({"inverted_tets", static_cast<double>(sys.inverted_tets())});
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    f.stats.insert(f.stats.end(),
                   {{"steps", static_cast<double>(s.steps)},
                    {"newton_iterations", static_cast<double>(s.newton_iterations)},
                    {"jacobian_evaluations", static_cast<double>(s.jacobian_evals)},
                    {"rejected_steps_error_test", static_cast<double>(s.error_test_failures)},
                    {"rejected_steps_newton", static_cast<double>(s.newton_failures)},
                    {"order", static_cast<double>(s.order)},
                    {sc.integrator.kind == IntegratorKind::statics ? "residual_norm" : "step_size", s.step_size},
                    {"wall_seconds", wall},
                    {"resident_mb", resident_memory_mb()}});
    w.write_frame(f);
    summary.frames = k + 1;
    if (progress) bar.update(k, t);
  };
}

}  // namespace

RunSummary run_scene(const Scene& sc, const std::string& output, bool progress) {
  RunSummary summary;
  summary.output = output.empty() ? sc.output.path : output;
  const std::unique_ptr<SceneSystem> sys = make_scene_system(sc);
  const std::unique_ptr<Integrator> integrator = make_integrator(sc, *sys);
  // (The mass-spring model has no zones: its scene is refused with any.)
  OutputWriter w(summary.output, sc.mesh, sc.zones, {sc.file.text_as_run(), sc.file.name(), "run"},
                 sc.output.pressure && sys->has_tets());
  const std::vector<double> times = sc.frames.times();
  Progress bar(sc.file.name(), static_cast<int>(times.size()) - 1, progress ? stderr : nullptr);
  try {
    summary.stats = integrator->run(times, frame_writer(sc, *sys, w, bar, summary, progress));
  } catch (const IntegrationError& e) {
    w.set_stat("failed_at_time", e.time);
    w.set_stat("failure", std::string(e.what()));
    w.close();
    throw Error(sc.file.name() + ": " + e.what() + "; " + std::to_string(summary.frames) + " frames saved in " +
                summary.output);
  }
  write_totals(w, summary.stats);
  if (sc.skeleton) {
    summary.simbody_seconds = sc.skeleton->simbody_seconds();
    w.set_stat("simbody_seconds", summary.simbody_seconds);
    w.set_stat("simbody_realizations", static_cast<double>(sc.skeleton->realizations()));
  }
  w.close();
  bar.finish();
  return summary;
}

}  // namespace isochor
