// integrator.kind = "mass_spring": Hong et al.'s step for material.model = "mass_spring".
#include "entries.hpp"

#include "isochor/integrators/hong_step.hpp"
#include "isochor/scene/mass_spring_system.hpp"

namespace isochor {

void parse_hong(const Section& in, IntegratorKind, IntegratorSpec& spec) {
  spec.hong.dt = parse_dt(in);
  spec.hong.max_steps = parse_max_steps(in);
  spec.weights_center = in.vec3("weights_center");
  spec.weights_radius = in.number("weights_radius");
}

std::unique_ptr<Integrator> make_hong(const Scene& scene, SceneSystem& system) {
  // The scene parser allows this kind only with material.model = "mass_spring".
  auto& springs = dynamic_cast<MassSpringSystem&>(system);
  HongOptions o = scene.integrator.hong;
  o.weighted_rows = springs.volume_rows();
  if (scene.integrator.weights_radius > 0) {
    VectorXd q, v;
    springs.initial_state(scene.frames.times().front(), q, v);
    o.weights = springs.weights(scene.integrator.weights_center, scene.integrator.weights_radius);
  }
  return std::make_unique<HongStep>(springs, o);
}

}  // namespace isochor
