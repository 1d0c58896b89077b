#include "isochor/integrators/fixed_step.hpp"
#include "isochor/integrators/interrupt.hpp"
#include "timing.hpp"

#include <algorithm>

namespace isochor {

void run_fixed_steps(const std::vector<double>& times, double h, long max_steps, VectorXd q, VectorXd v,
                     VectorXd lambda, const FixedStep& step, RunStats& stats,
                     const std::function<RunStats::FrameSample()>& sample, const FrameCallback& on_frame,
                     const FrameCorrection& between) {
  const auto wall0 = Clock::now();
  VectorXd q1, v1, l1 = lambda;
  const double t0 = times.front();
  double t = t0;
  std::size_t k = 0;
  stats.steps = 0;
  while (k < times.size() && times[k] <= t + 1e-12 * h) {
    on_frame(static_cast<int>(k), times[k], q, v, lambda, sample());
    ++k;
  }
  while (k < times.size()) {
    step_boundary(t);
    std::string reason;
    const double t1 = t0 + static_cast<double>(stats.steps + 1) * h;
    if (!step(t, t1, q, v, q1, v1, l1, reason)) {
      stats.wall_seconds = seconds_since(wall0);
      throw IntegrationError(
          t1, reason + " (step " + std::to_string(stats.steps + 1) + ", h = " + std::to_string(h) + " s)");
    }
    if (++stats.steps > max_steps) throw IntegrationError(t1, "more than " + std::to_string(max_steps) + " steps");
    while (k < times.size() && times[k] <= t1 + 1e-9 * h) {
      // A frame within rounding of a step's end (or start) is that step's state, not a blend.
      double w = std::clamp((times[k] - t) / h, 0.0, 1.0);
      if (w > 1.0 - 1e-9) w = 1.0;
      if (w < 1e-9) w = 0.0;
      VectorXd qf = (1 - w) * q + w * q1, vf = (1 - w) * v + w * v1;
      if (between && w > 0.0 && w < 1.0) between(times[k], qf, vf);
      on_frame(static_cast<int>(k), times[k], qf, vf, l1, sample());
      ++k;
    }
    q.swap(q1);
    v.swap(v1);
    lambda = l1;
    t = t1;
  }
  stats.wall_seconds = seconds_since(wall0);
}

}  // namespace isochor
