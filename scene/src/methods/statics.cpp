// integrator.kind = "static": KINSOL on the KKT system, one solve per load increment.
#include "entries.hpp"

#include "isochor/integrators/statics.hpp"

namespace isochor {

void parse_statics(const Section& in, IntegratorKind, IntegratorSpec& spec) {
  spec.statics.linear_solver = parse_linear_solver(in, LinearSolverKind::klu);
  spec.statics_linear_solver_auto = linear_solver_is_auto(in);
  // Load increments are pseudo-time: halving a failed one changes no accuracy, so it is on.
  spec.statics.substeps_on_failure = static_cast<int>(in.integer("substeps_on_failure", 5, 0, 30));
}

// linear_solver = "auto" for statics: KLU on the KKT matrix, but above 64 constraint rows (1-ring
// zones, fine patches, rollers: one row per node) `reduced`, whose sparse border
// (integrators/src/bordered.hpp) factors A + G^T D G with CHOLMOD's supernodal Cholesky where KLU
// factors the KKT matrix without BLAS-3. Measured (bench/zones_cost.sh, docs/results/zones_cost.md,
// one thread, medians of 3), Cook's membrane (a roller row on every node) at N = 32, 12,974 tets:
// 17.3 s on KLU against 3.2 s with the rows alone, 99.3 s against 12.7 s with 3,267 1-ring zones;
// at N = 64, 97,802 tets, 1,134 s against 47 s with the rows alone. At most 64 rows the dense
// border would need A alone to be definite and m + 1 solves per setup: KLU stays.
constexpr Index kAutoSparseBorderMinConstraints = 65;

LinearSolverKind automatic_static_solver(const ConstrainedSystem& system) {
  return system.dofs_per_group() == 3 && system.num_constraints() >= kAutoSparseBorderMinConstraints
             ? LinearSolverKind::reduced
             : LinearSolverKind::klu;
}

std::unique_ptr<Integrator> make_statics(const Scene& scene, SceneSystem& system) {
  StaticOptions o = scene.integrator.statics;
  if (scene.integrator.statics_linear_solver_auto) o.linear_solver = automatic_static_solver(system);
  return std::make_unique<StaticSolver>(system, o);
}

}  // namespace isochor
