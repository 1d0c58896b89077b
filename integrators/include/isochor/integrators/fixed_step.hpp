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

}  // namespace isochor
