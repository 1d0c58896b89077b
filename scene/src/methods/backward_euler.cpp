// integrator.kind = "backward_euler" or "semi_implicit": fixed steps, Newton on the KKT system.
#include "entries.hpp"

#include "isochor/integrators/backward_euler.hpp"

namespace isochor {

void parse_backward_euler(const Section& in, IntegratorKind kind, IntegratorSpec& spec) {
  BackwardEulerOptions& o = spec.backward_euler;
  o.dt = parse_dt(in);
  o.newton_tol = in.number("newton_tol");
  o.newton_atol = in.number("newton_atol");
  o.semi_implicit = kind == IntegratorKind::semi_implicit;
  o.max_steps = parse_max_steps(in);
  o.rescale_volume = in.boolean("rescale_volume", false);
  if (o.rescale_volume && kind != IntegratorKind::backward_euler && kind != IntegratorKind::semi_implicit)
    refuse_option(in, "rescale_volume", "is an option of the backward_euler and semi_implicit integrators");
  o.linear_solver = parse_linear_solver(in, LinearSolverKind::reduced);
  o.automatic_linear_solver = kind == IntegratorKind::backward_euler && linear_solver_is_auto(in);
  o.linear_tol = in.number("linear_tol");
  const std::string hessian = in.string("hessian");
  o.project_hessian = hessian != "exact";
  o.exact_near_solution = hessian == "hybrid";
  if (o.exact_near_solution && kind == IntegratorKind::semi_implicit)
    in.fail("hessian",
            "\"hybrid\" switches within backward Euler's Newton iteration (the semi-implicit step takes one update)");
  if (kind != IntegratorKind::backward_euler && kind != IntegratorKind::semi_implicit)
    refuse_option(in, "hessian", "is an option of the backward_euler and semi_implicit integrators");
  // Options of backward Euler's Newton iteration alone (semi-implicit takes one update).
  o.max_newton = static_cast<int>(in.integer("max_newton", 30));
  o.line_search = in.boolean("line_search", true);
  o.substeps_on_failure = static_cast<int>(in.integer("substeps_on_failure", 0));
  o.schur_max_constraints =
      static_cast<int>(in.integer("dense_border_rows", BackwardEulerOptions::kDefaultDenseBorderRows));
  if (kind != IntegratorKind::backward_euler && kind != IntegratorKind::semi_implicit)
    refuse_option(in, "dense_border_rows", "is an option of the backward_euler and semi_implicit integrators");
  if (kind != IntegratorKind::backward_euler)
    refuse_option(in, "line_search", "is an option of the backward_euler integrator");
  if (kind != IntegratorKind::backward_euler && kind != IntegratorKind::statics)
    refuse_option(in, "substeps_on_failure", "is an option of the backward_euler and static integrators");
  if (kind != IntegratorKind::backward_euler && kind != IntegratorKind::ida)
    refuse_option(in, "max_newton", "is an option of the backward_euler and ida integrators");
}

std::unique_ptr<Integrator> make_backward_euler(const Scene& scene, SceneSystem& system) {
  return std::make_unique<BackwardEuler>(system, scene.integrator.backward_euler);
}

}  // namespace isochor
