// integrator.kind = "backward_euler" or "semi_implicit": fixed steps, Newton on the KKT system.
#include "registry.hpp"

namespace isochor {

BackwardEulerOptions backward_euler_options(const IntegratorSpec& s) {
  BackwardEulerOptions o;
  o.dt = s.dt;
  o.newton_tol = s.newton_tol;
  o.newton_atol = s.newton_atol;
  o.semi_implicit = s.kind == IntegratorKind::semi_implicit;
  o.max_steps = s.max_steps;
  o.rescale_volume = s.rescale_volume;
  o.linear_solver = s.linear_solver;
  return o;
}

std::unique_ptr<Integrator> make_backward_euler(const Scene& scene, SceneSystem& system) {
  return std::make_unique<BackwardEuler>(system, backward_euler_options(scene.integrator));
}

}  // namespace isochor
