// integrator.kind = "static": KINSOL on the KKT system, one solve per load increment.
#include "registry.hpp"

namespace isochor {

StaticOptions static_options(const IntegratorSpec& s) {
  StaticOptions o;
  o.linear_solver = s.linear_solver;
  return o;
}

std::unique_ptr<Integrator> make_statics(const Scene& scene, SceneSystem& system) {
  return std::make_unique<StaticSolver>(system, static_options(scene.integrator));
}

}  // namespace isochor
