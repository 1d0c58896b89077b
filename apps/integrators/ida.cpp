// integrator.kind = "ida": the GGL DAE on SUNDIALS IDA.
#include "registry.hpp"

namespace isochor {

IdaOptions ida_options(const IntegratorSpec& s) {
  IdaOptions o;
  o.rtol = s.rtol;
  o.atol_q = s.atol;
  o.atol_v = s.atol_v;
  o.atol_lambda = s.atol_lambda;
  o.max_order = s.max_order;
  o.max_step = s.max_step;
  o.newton_coef = s.newton_coef;
  o.max_steps = s.max_steps;
  o.ordering = s.ordering;
  o.linear_solver = s.linear_solver;
  o.jacobian_age = s.jacobian_age;
  return o;
}

std::unique_ptr<Integrator> make_ida(const Scene& scene, SceneSystem& system) {
  return std::make_unique<IdaIntegrator>(system, ida_options(scene.integrator));
}

}  // namespace isochor
