#include "run.hpp"

#include <sys/resource.h>

#include <chrono>
#include <type_traits>

#include "isochor/backward_euler.hpp"
#include "isochor/error.hpp"
#include "isochor/mesh_system.hpp"
#include "isochor/output.hpp"
#include "isochor/progress.hpp"
#include "isochor/statics.hpp"
#include "isochor/xpbd_system.hpp"
#include "isochor/hong_step.hpp"
#include "isochor/mass_spring_system.hpp"

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
  w.set_stat("reused_jacobians", static_cast<double>(s.reused_jacobians));
  w.set_stat("linear_fallbacks", static_cast<double>(s.linear_fallbacks));
  w.set_stat("wall_seconds", s.wall_seconds);
  w.set_stat("assembly_seconds", s.assembly_seconds);
  w.set_stat("factorisation_seconds", s.factor_seconds);
  w.set_stat("solve_seconds", s.solve_seconds);
  w.set_stat("factor_nnz", s.factor_nnz);
  w.set_stat("symbolic_seconds", s.symbolic_seconds);
  w.set_stat("linear_iterations", static_cast<double>(s.linear_iterations));
  // Peak resident memory of the whole process (getrusage), for the linear-solver benchmarks.
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  w.set_stat("peak_memory_mb", static_cast<double>(ru.ru_maxrss) / 1024.0);
}
}  // namespace

namespace {

// Runs the scene's integrator on a system (MeshSystem or MassSpringSystem: both give positions,
// energies and volumes of a state) and writes every frame.
template <class System>
RunSummary run_system(const Scene& sc, System& sys, const std::string& output, bool progress) {
  const std::string& kind = sc.integrator.kind;
  RunSummary summary;
  summary.output = output;
  IdaOptions o;
  o.rtol = sc.integrator.rtol;
  o.atol_q = sc.integrator.atol;
  o.max_order = sc.integrator.max_order;
  o.max_step = sc.integrator.max_step;
  o.newton_coef = sc.integrator.newton_coef;
  o.max_steps = sc.integrator.max_steps;
  o.ordering = sc.integrator.ordering;
  o.linear_solver = sc.integrator.linear_solver == "auto" ? "klu" : sc.integrator.linear_solver;
  o.jacobian_age = sc.integrator.jacobian_age;
  BackwardEulerOptions be;
  be.dt = sc.integrator.dt;
  be.newton_tol = sc.integrator.newton_tol;
  be.semi_implicit = kind == "semi_implicit";
  be.max_steps = sc.integrator.max_steps;
  be.rescale_volume = sc.integrator.rescale_volume;
  be.linear_solver = sc.integrator.linear_solver == "auto" ? "reduced" : sc.integrator.linear_solver;
  const bool mass_spring = sc.material.model == "mass_spring";
  OutputWriter w(summary.output, sc.mesh, mass_spring ? decltype(sc.zones){} : sc.zones,
                 {sc.file.text_as_run(), sc.file.name(), "run"}, sc.output.pressure && !mass_spring);
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
    if constexpr (std::is_same_v<System, MeshSystem>) {
      if (sc.output.pressure) {
        sys.pressures(lambda, pressure);
        f.pressure = &pressure;
      }
      f.stats.push_back({"inverted_tets", static_cast<double>(sys.inverted_tets())});
    }
    const std::vector<std::pair<std::string, double>> more = {
        {"steps", static_cast<double>(s.steps)},
        {"newton_iterations", static_cast<double>(s.newton_iterations)},
        {"jacobian_evaluations", static_cast<double>(s.jacobian_evals)},
        {"rejected_steps_error_test", static_cast<double>(s.error_test_failures)},
        {"rejected_steps_newton", static_cast<double>(s.newton_failures)},
        {"order", static_cast<double>(s.order)},
        {kind == "static" ? "residual_norm" : "step_size", s.step_size},
        {"wall_seconds", std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()}};
    f.stats.insert(f.stats.end(), more.begin(), more.end());
    w.write_frame(f);
    summary.frames = k + 1;
    if (progress) bar.update(k, t);
  };
  try {
    if (kind == "ida") summary.stats = IdaIntegrator(sys, o).run(times, on_frame);
    else if (kind == "static") {
      StaticOptions so;
      so.linear_solver = sc.integrator.linear_solver == "auto" ? "klu" : sc.integrator.linear_solver;
      summary.stats = StaticSolver(sys, so).run(times, on_frame);
    }
    else if (kind == "backward_euler" || kind == "semi_implicit") summary.stats = BackwardEuler(sys, be).run(times, on_frame);
    else if (kind == "mass_spring") {
      if constexpr (std::is_same_v<System, MassSpringSystem>) {
        HongOptions ho;
        ho.dt = sc.integrator.dt;
        ho.max_steps = sc.integrator.max_steps;
        if (sc.integrator.weights_radius > 0) {
          VectorXd q, v;
          sys.initial_state(times.front(), q, v);
          ho.weights = sys.weights(sc.integrator.weights_center, sc.integrator.weights_radius);
        }
        summary.stats = HongStep(sys, ho).run(times, on_frame);
      }
    } else if (kind == "xpbd") {
      if constexpr (std::is_same_v<System, MeshSystem>) {
        // XPBD works on every node; frames are written through the mesh system's free dofs.
        XpbdOptions xo;
        xo.dt = sc.integrator.dt;
        xo.substeps = sc.integrator.substeps;
        xo.iterations = sc.integrator.iterations;
        xo.max_steps = sc.integrator.max_steps;
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
    }
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

}  // namespace

RunSummary run_scene(const Scene& sc, const std::string& output, bool progress) {
  const std::string& kind = sc.integrator.kind;
  if ((kind == "static") != (sc.frames.count > 0))
    throw Error(sc.file.name() + (kind == "static" ? ": a static run needs frames.count (load increments)"
                                                   : ": frames.count is for statics; a dynamic run needs frames.rate and frames.duration"));
  const bool mass_spring = sc.material.model == "mass_spring";
  if (kind == "xpbd" && mass_spring)
    throw Error(sc.file.name() + ": integrator.kind = \"xpbd\" needs a tet material (expected material.model other than \"mass_spring\")");
  if (kind == "mass_spring" && !mass_spring)
    throw Error(sc.file.name() + ": integrator.kind = \"mass_spring\" is Hong et al.'s step for material.model = \"mass_spring\"");
  const std::string out = output.empty() ? sc.output.path : output;
  if (mass_spring) {
    MassSpringSystem sys(sc);
    return run_system(sc, sys, out, progress);
  }
  MeshSystem sys(sc);
  return run_system(sc, sys, out, progress);
}

}  // namespace isochor
