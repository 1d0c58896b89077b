// The frame loop shared by the fixed-step integrators (backward Euler, XPBD, Hong's mass-spring
// step): step from frame_times.front() with step h, deliver frames between steps by linear
// interpolation of (q, v) (exact at step times; multipliers of the step's end; optionally
// corrected, below), and report a
// failed step as an IntegrationError at the time it was aiming for. Step k ends at t0 + k h
// (computed, not accumulated).
#pragma once
#include <functional>
#include <string>

#include "isochor/integrators/constrained_system.hpp"
#include "isochor/integrators/run_stats.hpp"

namespace isochor {

// One step from (q, v, lambda) at t to t1 (= t + h up to rounding), into (q1, v1, lambda1);
// false with a reason.
using FixedStep = std::function<bool(double t, double t1, const VectorXd& q, const VectorXd& v, VectorXd& q1,
                                     VectorXd& v1, VectorXd& lambda1, std::string& reason)>;

// Runs the loop from the initial state; `stats` gets steps and wall time, and `sample` is called
// for each frame's statistics (with stats.steps up to date). `between`, when given, corrects a
// frame that falls strictly between two steps (t, q, v) after the linear interpolation: backward
// Euler projects it onto the constraints, which an interpolation does not keep.
using FrameCorrection = std::function<void(double t, VectorXd& q, VectorXd& v)>;
void run_fixed_steps(const std::vector<double>& frame_times, double h, long max_steps, VectorXd q, VectorXd v,
                     VectorXd lambda, const FixedStep& step, RunStats& stats,
                     const std::function<RunStats::FrameSample()>& sample, const FrameCallback& on_frame,
                     const FrameCorrection& between = nullptr);

// The same loop a step at a time (the fixed-step integrators' SteppingIntegrator interface):
// begin() delivers the frames at the start; step(t_out) steps until the time reached is at least
// t_out (at most the last frame time; within 1e-9 h, the tolerance by which a frame belongs to a
// step's end), delivering every frame passed, and returns that time. run_fixed_steps is begin and
// step to the last frame. `stats` (steps, wall time) must outlive the stepper.
class FixedStepper {
 public:
  FixedStepper(std::vector<double> frame_times, double h, long max_steps, FixedStep step, RunStats& stats,
               std::function<RunStats::FrameSample()> sample, FrameCallback on_frame,
               FrameCorrection between = nullptr);
  void begin(VectorXd q, VectorXd v, VectorXd lambda);
  double step(double t_out);

 private:
  void deliver_up_to(double t1);
  std::vector<double> times_;
  double h_;
  long max_steps_;
  FixedStep step_;
  RunStats& stats_;
  std::function<RunStats::FrameSample()> sample_;
  FrameCallback on_frame_;
  FrameCorrection between_;
  VectorXd q_, v_, lambda_, q1_, v1_, l1_;
  double t_ = 0;
  std::size_t k_ = 0;  // the next frame to deliver
};

}  // namespace isochor
