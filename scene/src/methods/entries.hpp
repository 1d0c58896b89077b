// Each integrator's parser and factory (one file each), and the keys several of them share.
#pragma once
#include "isochor/scene/integrator_registry.hpp"

namespace isochor {

void parse_ida(const Section& in, IntegratorKind kind, IntegratorSpec& spec);
void parse_statics(const Section& in, IntegratorKind kind, IntegratorSpec& spec);
void parse_backward_euler(const Section& in, IntegratorKind kind, IntegratorSpec& spec);
void parse_xpbd(const Section& in, IntegratorKind kind, IntegratorSpec& spec);
void parse_hong(const Section& in, IntegratorKind kind, IntegratorSpec& spec);
std::unique_ptr<Integrator> make_ida(const Scene& scene, SceneSystem& system);
std::unique_ptr<Integrator> make_statics(const Scene& scene, SceneSystem& system);
std::unique_ptr<Integrator> make_backward_euler(const Scene& scene, SceneSystem& system);
std::unique_ptr<Integrator> make_xpbd(const Scene& scene, SceneSystem& system);
std::unique_ptr<Integrator> make_hong(const Scene& scene, SceneSystem& system);

// integrator.max_steps (every integrator), integrator.dt (the fixed-step ones), and
// integrator.linear_solver with "auto" standing for `automatic`.
long parse_max_steps(const Section& in);
double parse_dt(const Section& in);
LinearSolverKind parse_linear_solver(const Section& in, LinearSolverKind automatic);
// Whether integrator.linear_solver is "auto" (or unset).
bool linear_solver_is_auto(const Section& in);
// An option that the integrator of this kind does not take: set, it stops the scene with
// `message`, unless integrator.kind came from --set and the option from the file (a scene written
// for one method, run as a variant of another, leaves its own method's options unused).
void refuse_option(const Section& in, std::string_view key, const std::string& message);

}  // namespace isochor
