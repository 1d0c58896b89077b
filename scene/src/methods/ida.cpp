// integrator.kind = "ida": the GGL DAE on SUNDIALS IDA (keys in docs/scenes.md).
#include "entries.hpp"

#include "isochor/integrators/ida_integrator.hpp"

namespace isochor {

void parse_ida(const Section& in, IntegratorKind kind, IntegratorSpec& spec) {
  IdaOptions& o = spec.ida;
  // A relative tolerance above 1 and an absolute one longer than a body accept any step.
  o.rtol = in.number("rtol");
  o.atol_q = in.number("atol");
  o.atol_v = in.number("atol_v");
  o.atol_lambda = in.number("atol_lambda");
  o.max_order = static_cast<int>(in.integer("max_order"));
  o.max_step = in.number("max_step");
  // Unset: 0, the integrator's default (IdaOptions::kDefaultNewtonCoef, every linear solver).
  o.newton_coef = in.has("newton_coef") ? in.number("newton_coef", IdaOptions::kDefaultNewtonCoef) : 0.0;
  // Read here for IDA only (backward Euler's parser reads the key with its own default and range).
  if (kind == IntegratorKind::ida) {
    o.max_newton = static_cast<int>(in.integer("max_newton", 4));
    if (o.max_newton > 100)
      in.fail("max_newton", "expected an integer in [1, 100], got " + std::to_string(o.max_newton));
  }
  o.max_steps = parse_max_steps(in);
  const std::string ordering = in.string("ordering");
  o.ordering = ordering == "colamd" ? KluOrdering::colamd : ordering == "amd" ? KluOrdering::amd : KluOrdering::metis;
  o.linear_solver = parse_linear_solver(in, LinearSolverKind::klu);
  spec.ida_linear_solver_auto = linear_solver_is_auto(in);
  o.jacobian_age = in.integer("jacobian_age");
  o.linear_tol = in.number("linear_tol");
  o.stop_at_frames = in.boolean("stop_at_frames", false);
}

// linear_solver = "auto" for IDA. Measured (bench/linear_solvers.sh, the ball through its impact,
// docs/results/linear_solvers.md): krylov is faster than klu at every size tried, 2.5 times at
// 320 tets, 5 at 966, 13 at 2K and 48 at 4.5K, and faster than reduced from 966 tets up
// (docs/results/scaling.md). The reduced solvers carry each constraint row as dense columns
// (7 n x m matrices) and solve with S 2m times per setup, so their cost grows with the rows:
// with one patch zone per 1-ring (zones.patches = 1, a free box, 20 ms) krylov still took 1.0 s
// against klu's 2.5 s at 65 zones (1.7K tets) and 6.2 s against 29.4 s at 125 zones (6K tets), a
// cost of ~0.05 s per zone there (klu was then KLU on the GGL matrix). Above 256 rows (1-ring
// zones: one per node) klu, which above 32 rows solves through the KKT matrix (ggl_kkt.hpp).
// Against that path the crossover depends on the rows' width and on the setups per step: the
// same box's 125 patches, 9 setups in 11 steps, took 8.9 s on krylov and 1.0 s on klu; the
// 21,870-tet beam's 108 2-ring patches, 5 setups in 261 steps, 12.2 s and 28.7 s (single runs,
// one thread). One threshold on the row count cannot place both; it stays at 256.
constexpr int kAutoKrylovMaxConstraints = 256;

LinearSolverKind automatic_ida_solver(const ConstrainedSystem& system) {
  if (system.partition()) return LinearSolverKind::krylov;  // the solver whose work MPI ranks split
  return system.dofs_per_group() == 3 && system.num_constraints() <= kAutoKrylovMaxConstraints
             ? LinearSolverKind::krylov
             : LinearSolverKind::klu;
}

std::unique_ptr<Integrator> make_ida(const Scene& scene, SceneSystem& system) {
  IdaOptions o = scene.integrator.ida;
  if (scene.integrator.ida_linear_solver_auto) o.linear_solver = automatic_ida_solver(system);
  return std::make_unique<IdaIntegrator>(system, o);
}

}  // namespace isochor
