// integrator.kind = "mass_spring": Hong et al.'s step for material.model = "mass_spring".
#include "registry.hpp"

#include "isochor/mass_spring_system.hpp"

namespace isochor {

HongOptions hong_options(const IntegratorSpec& s) {
  HongOptions o;
  o.dt = s.dt;
  o.max_steps = s.max_steps;
  return o;
}

std::unique_ptr<Integrator> make_hong(const Scene& scene, SceneSystem& system) {
  // The scene parser allows this kind only with material.model = "mass_spring".
  auto& springs = dynamic_cast<MassSpringSystem&>(system);
  HongOptions o = hong_options(scene.integrator);
  if (scene.integrator.weights_radius > 0) {
    VectorXd q, v;
    springs.initial_state(scene.frames.times().front(), q, v);
    o.weights = springs.weights(scene.integrator.weights_center, scene.integrator.weights_radius);
  }
  return std::make_unique<HongStep>(springs, o);
}

}  // namespace isochor
