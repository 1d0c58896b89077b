// Running a scene end to end: scene -> its system -> its integrator (by kind) -> output file.
#pragma once
#include <string>

#include "isochor/run_stats.hpp"
#include "isochor/scene.hpp"

namespace isochor {

struct RunSummary {
  std::string output;
  int frames = 0;
  RunStats stats;
  double simbody_seconds = 0;  // realizing the skeleton (0 without one)
};

// Runs the scene and writes every frame to `output` (scene's output.path when empty). A solver
// failure keeps the frames written so far and throws Error naming the time and the reason.
RunSummary run_scene(const Scene& scene, const std::string& output = "", bool progress = true);

}  // namespace isochor
