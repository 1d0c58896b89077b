#include "registry.hpp"

#include "isochor/error.hpp"

namespace isochor {

const std::map<IntegratorKind, IntegratorFactory>& integrator_registry() {
  static const std::map<IntegratorKind, IntegratorFactory> r = {
      {IntegratorKind::ida, make_ida},
      {IntegratorKind::statics, make_statics},
      {IntegratorKind::backward_euler, make_backward_euler},
      {IntegratorKind::semi_implicit, make_backward_euler},
      {IntegratorKind::xpbd, make_xpbd},
      {IntegratorKind::mass_spring, make_hong},
  };
  return r;
}

std::unique_ptr<Integrator> make_integrator(const Scene& scene, SceneSystem& system) {
  const auto& r = integrator_registry();
  const auto it = r.find(scene.integrator.kind);
  if (it == r.end()) throw Error(scene.file.name() + ": integrator.kind = \"" + to_string(scene.integrator.kind) + "\" has no integrator");
  return it->second(scene, system);
}

}  // namespace isochor
