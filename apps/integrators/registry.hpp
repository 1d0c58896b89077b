// The integrators by name (integrator.kind = ida | static | backward_euler | semi_implicit | xpbd
// | mass_spring). Each has its own file here that turns the scene's [integrator] settings into
// its options and builds it on the scene's system; the registry maps the kind to that factory.
#pragma once
#include <map>
#include <memory>

#include "isochor/backward_euler.hpp"
#include "isochor/hong_step.hpp"
#include "isochor/ida_integrator.hpp"
#include "isochor/integrator.hpp"
#include "isochor/scene.hpp"
#include "isochor/scene_system.hpp"
#include "isochor/statics.hpp"
#include "isochor/xpbd.hpp"

namespace isochor {

using IntegratorFactory = std::unique_ptr<Integrator> (*)(const Scene&, SceneSystem&);
const std::map<IntegratorKind, IntegratorFactory>& integrator_registry();
// The scene's integrator on its system (which must outlive it).
std::unique_ptr<Integrator> make_integrator(const Scene& scene, SceneSystem& system);

// Each integrator's options from the scene's settings (one file each).
IdaOptions ida_options(const IntegratorSpec& s);
StaticOptions static_options(const IntegratorSpec& s);
BackwardEulerOptions backward_euler_options(const IntegratorSpec& s);
XpbdOptions xpbd_options(const IntegratorSpec& s);
HongOptions hong_options(const IntegratorSpec& s);

std::unique_ptr<Integrator> make_ida(const Scene& scene, SceneSystem& system);
std::unique_ptr<Integrator> make_statics(const Scene& scene, SceneSystem& system);
std::unique_ptr<Integrator> make_backward_euler(const Scene& scene, SceneSystem& system);
std::unique_ptr<Integrator> make_xpbd(const Scene& scene, SceneSystem& system);
std::unique_ptr<Integrator> make_hong(const Scene& scene, SceneSystem& system);

}  // namespace isochor
