// Helpers of the tests that run scenes: a scene's frames with the system at each, and the bar on
// three symmetry planes that the uniaxial checks share.
#pragma once
#include "isochor/scene/integrator_registry.hpp"
#include "isochor/scene/scene.hpp"
#include "isochor/scene/scene_system.hpp"

namespace isochor::test {

// Runs a scene and calls f(t, system, q, lambda) at every frame, the system set to the frame's
// state.
template <class F>
void run_frames(const Scene& sc, F&& f) {
  auto sys = make_scene_system(sc);
  auto integrator = make_integrator(sc, *sys);
  integrator->run(sc.frames.times(), [&](int, double t, const VectorXd& q, const VectorXd& v, const VectorXd& lambda,
                                         const RunStats::FrameSample&) {
    sys->set_state(t, q, v);
    f(t, *sys, q, lambda);
  });
}

// A bar 1 x 0.5 x 0.5 m, its corner at the origin, on rollers at x = 0, y = 0 and z = 0; CNH
// (mu = 1 kPa) with one global zone, no gravity, statics in 11 increments: its homogeneous
// uniaxial states have closed forms.
inline const char* const kRollerBar = R"(
[mesh]
shape = "box"
cells = [3, 2, 2]
size = [1.0, 0.5, 0.5]
center = [0.5, 0.25, 0.25]
[material]
model = "cnh"
mu = 1000.0
lambda = 5000.0
[zones]
global = true
[forces]
gravity = [0.0, 0.0, 0.0]
[[boundary]]
select = { kind = "set", name = "xmin" }
components = ["x"]
[[boundary]]
select = { kind = "set", name = "ymin" }
components = ["y"]
[[boundary]]
select = { kind = "set", name = "zmin" }
components = ["z"]
[integrator]
kind = "static"
[frames]
count = 11
)";

}  // namespace isochor::test
