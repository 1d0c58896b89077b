// Running a dynamic scene end to end: scene -> MeshSystem -> integrator -> output file.
#pragma once
#include <string>

#include "isochor/ida_integrator.hpp"
#include "isochor/scene.hpp"

namespace isochor {

struct RunSummary {
  std::string output;
  int frames = 0;
  IdaStats stats;
  double simbody_seconds = 0;  // realizing the skeleton (0 without one)
};

// Runs the scene and writes every frame to `output` (scene's output.path when empty). A solver
// failure keeps the frames written so far and throws Error naming the time and the reason.
RunSummary run_scene(const Scene& scene, const std::string& output = "", bool progress = true);

}  // namespace isochor
