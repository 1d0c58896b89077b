// integrator.kind = "static": KINSOL on the KKT system, one solve per load increment.
#include "entries.hpp"

#include "isochor/integrators/statics.hpp"

namespace isochor {

void parse_statics(const Section& in, IntegratorKind, IntegratorSpec& spec) {
  spec.statics.linear_solver = parse_linear_solver(in, LinearSolverKind::klu);
  spec.statics_linear_solver_auto = linear_solver_is_auto(in);
  // Load increments are pseudo-time: halving a failed one changes no accuracy, so it is on.
  spec.statics.substeps_on_failure = static_cast<int>(in.integer("substeps_on_failure", 5));
}

std::unique_ptr<Integrator> make_statics(const Scene& scene, SceneSystem& system) {
  StaticOptions o = scene.integrator.statics;
  if (scene.integrator.statics_linear_solver_auto) o.linear_solver = automatic_static_solver(system);
  return std::make_unique<StaticSolver>(system, o);
}

}  // namespace isochor
