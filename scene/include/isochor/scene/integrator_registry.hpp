// The integrators by name (integrator.kind = ida | static | backward_euler | semi_implicit | xpbd
// | mass_spring). Each has its own file in models/src/integrators/ that parses its options from
// the scene's [integrator] table (resolving linear_solver = "auto" to its own default) and builds
// it on the scene's system; the registry lists them. Every integrator's parser reads every scene,
// so each key is checked whatever the kind, and one scene switches kind by --set alone.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "isochor/integrators/integrator.hpp"
#include "isochor/scene/scene.hpp"
#include "isochor/scene/scene_system.hpp"

namespace isochor {

struct IntegratorEntry {
  IntegratorKind kind;
  const char* name;  // the value of integrator.kind
  // Reads this integrator's keys of [integrator] into its member of the spec.
  void (*parse)(const Section& in, IntegratorKind kind, IntegratorSpec& spec);
  // Builds it on the scene's system (which must outlive it).
  std::unique_ptr<Integrator> (*make)(const Scene& scene, SceneSystem& system);
};

const std::vector<IntegratorEntry>& integrator_registry();
const IntegratorEntry& integrator_entry(IntegratorKind kind);
// The scene's integrator on its system.
std::unique_ptr<Integrator> make_integrator(const Scene& scene, SceneSystem& system);
// Stops with one line naming the key where the scene asks for what runs on one process only: a
// scene on MPI ranks (ranks.hpp) runs IDA, backward Euler or the semi-implicit step on PCG.
void check_ranks(const Scene& scene);
// IDA's linear_solver = "auto" for a system (models/src/integrators/ida.cpp says why): krylov for
// 3-dof nodes with at most 256 constraint rows, else klu.
LinearSolverKind automatic_ida_solver(const ConstrainedSystem& system);

}  // namespace isochor
