// integrator.kind = "static": KINSOL on the KKT system, one solve per load increment.
#include "entries.hpp"

#include "isochor/statics.hpp"

namespace isochor {

void parse_statics(const Section& in, IntegratorKind, IntegratorSpec& spec) {
  spec.statics.linear_solver = parse_linear_solver(in, LinearSolverKind::klu);
}

std::unique_ptr<Integrator> make_statics(const Scene& scene, SceneSystem& system) {
  return std::make_unique<StaticSolver>(system, scene.integrator.statics);
}

}  // namespace isochor
