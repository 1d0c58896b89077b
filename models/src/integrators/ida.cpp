// integrator.kind = "ida": the GGL DAE on SUNDIALS IDA (keys in docs/scenes.md).
#include "entries.hpp"

#include "isochor/ida_integrator.hpp"

namespace isochor {

void parse_ida(const Section& in, IntegratorKind kind, IntegratorSpec& spec) {
  IdaOptions& o = spec.ida;
  o.rtol = in.number("rtol", 1e-6, Range::positive());
  o.atol_q = in.number("atol", 1e-8, Range::positive());
  o.atol_v = in.number("atol_v", 0.0, Range::non_negative());
  o.atol_lambda = in.number("atol_lambda", 0.0, Range::non_negative());
  o.max_order = static_cast<int>(in.integer("max_order", 5, 1, 5));
  o.max_step = in.number("max_step", 0.0, Range::non_negative());
  o.newton_coef = in.number("newton_coef", 0.33, {0.0, 1.0, true, true});
  // Read here for IDA only (backward Euler's parser reads the key with its own default and range).
  if (kind == IntegratorKind::ida) o.max_newton = static_cast<int>(in.integer("max_newton", 4, 1, 100));
  o.max_steps = parse_max_steps(in);
  const std::string ordering = in.string("ordering", "metis", {"metis", "colamd", "amd"});
  o.ordering = ordering == "colamd" ? KluOrdering::colamd : ordering == "amd" ? KluOrdering::amd : KluOrdering::metis;
  o.linear_solver = parse_linear_solver(in, LinearSolverKind::klu);
  o.jacobian_age = in.integer("jacobian_age", 0, 0, 1000000000L);
  o.stop_at_frames = in.boolean("stop_at_frames", false);
}

std::unique_ptr<Integrator> make_ida(const Scene& scene, SceneSystem& system) {
  return std::make_unique<IdaIntegrator>(system, scene.integrator.ida);
}

}  // namespace isochor
