// Running a scene end to end: scene -> its system -> its integrator (by kind) -> output file.
#pragma once
#include <functional>
#include <string>

#include "isochor/base/error.hpp"
#include "isochor/core/output.hpp"
#include "isochor/integrators/ranks.hpp"
#include "isochor/integrators/run_stats.hpp"
#include "isochor/scene/scene.hpp"

namespace isochor {

struct RunSummary {
  std::string output;
  int frames = 0;              // in the file (a resumed run: with the frames before the resume)
  RunStats stats;              // a resumed run: steps, Newton iterations, Jacobians, rejections and wall time
                               // include the part before the resume (from the file's per-frame series)
  double simbody_seconds = 0;  // realizing the skeleton (0 without one)
  int resumed_from = -1;       // the frame a resumed run continued from
  double resumed_time = 0;
  bool already_finished = false;  // --resume of a finished run: nothing was done
};

struct RunOptions {
  std::string output;  // the scene's output.path when empty
  bool progress = true;
  // create: an existing output is an error; overwrite: replaced; resume: continued from its last
  // complete frame (the scene must be the one it was written with).
  OutputWriter::Mode mode = OutputWriter::Mode::create;
  // Called after each frame is written (index, and the frame as written, with per-tet pressures
  // even when output.pressure is off); returning false stops the run there as an interrupt does
  // (status "interrupted", signal 0, RunInterrupted).
  std::function<bool(int, const Frame&)> on_frame;
  // Replaces the scene's muscle activations: called with each new time the solver evaluates (the
  // frames' times among them), one value per muscle in [0, 1]. What it returns at a frame is what
  // /frames/activation records.
  std::function<std::vector<double>(double)> activation;
  // On P MPI ranks (ranks.hpp; null or one rank: one process): every rank calls run_scene with
  // the same scene, rank 0 writes the file and the progress.
  const Ranks* ranks = nullptr;
};

// A run stopped by a signal (SIGINT, SIGTERM) at a step boundary: the frames so far are in the
// file, marked interrupted; `isochor run --resume` continues it.
class RunInterrupted : public Error {
 public:
  RunInterrupted(const std::string& message, int sig, RunSummary done = {})
      : Error(message), signal(sig), summary(std::move(done)) {}
  int signal;
  RunSummary summary;  // what was done: the frames kept and the statistics until the stop
};

// Runs the scene and writes every frame to the output. A solver failure keeps the frames written
// so far and throws Error naming the time and the reason; an interrupt throws RunInterrupted.
// OpenBLAS runs on one thread meanwhile unless OPENBLAS_NUM_THREADS is set, its count restored
// after (README, "Threads").
RunSummary run_scene(const Scene& scene, const RunOptions& options);

inline RunSummary run_scene(const Scene& scene, const std::string& output = "", bool progress = true) {
  RunOptions opt;
  opt.output = output;
  opt.progress = progress;
  return run_scene(scene, opt);
}

}  // namespace isochor
