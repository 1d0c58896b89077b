#include "isochor/integrators/fixed_step.hpp"
#include "isochor/integrators/interrupt.hpp"
#include "timing.hpp"

#include <algorithm>

namespace isochor {

void run_fixed_steps(const std::vector<double>& times, double h, long max_steps, VectorXd q, VectorXd v,
                     VectorXd lambda, const FixedStep& step, RunStats& stats,
                     const std::function<RunStats::FrameSample()>& sample, const FrameCallback& on_frame,
                     const FrameCorrection& between) {
  FixedStepper stepper(times, h, max_steps, step, stats, sample, on_frame, between);
  stepper.begin(std::move(q), std::move(v), std::move(lambda));
  stepper.step(times.back());
}

FixedStepper::FixedStepper(std::vector<double> frame_times, double h, long max_steps, FixedStep step, RunStats& stats,
                           std::function<RunStats::FrameSample()> sample, FrameCallback on_frame,
                           FrameCorrection between)
    : times_(std::move(frame_times)),
      h_(h),
      max_steps_(max_steps),
      step_(std::move(step)),
      stats_(stats),
      sample_(std::move(sample)),
      on_frame_(std::move(on_frame)),
      between_(std::move(between)) {}

void FixedStepper::begin(VectorXd q, VectorXd v, VectorXd lambda) {
  const auto wall0 = Clock::now();
  q_ = std::move(q);
  v_ = std::move(v);
  lambda_ = std::move(lambda);
  l1_ = lambda_;
  t_ = times_.front();
  k_ = 0;
  stats_.steps = 0;
  stats_.wall_seconds = 0;
  while (k_ < times_.size() && times_[k_] <= t_ + 1e-12 * h_) {
    on_frame_(static_cast<int>(k_), times_[k_], q_, v_, lambda_, sample_());
    ++k_;
  }
  stats_.wall_seconds += seconds_since(wall0);
}

// The frames up to the step just taken (t_ to t1), interpolated between its ends.
void FixedStepper::deliver_up_to(double t1) {
  while (k_ < times_.size() && times_[k_] <= t1 + 1e-9 * h_) {
    // A frame within rounding of a step's end (or start) is that step's state, not a blend.
    double w = std::clamp((times_[k_] - t_) / h_, 0.0, 1.0);
    if (w > 1.0 - 1e-9) w = 1.0;
    if (w < 1e-9) w = 0.0;
    VectorXd qf = (1 - w) * q_ + w * q1_, vf = (1 - w) * v_ + w * v1_;
    if (between_ && w > 0.0 && w < 1.0) between_(times_[k_], qf, vf);
    on_frame_(static_cast<int>(k_), times_[k_], qf, vf, l1_, sample_());
    ++k_;
  }
}

double FixedStepper::step(double t_out) {
  const auto wall0 = Clock::now();
  const double target = std::min(t_out, times_.back());
  while (k_ < times_.size() && t_ < target - 1e-9 * h_) {
    step_boundary(t_);
    std::string reason;
    const double t1 = times_.front() + static_cast<double>(stats_.steps + 1) * h_;
    if (!step_(t_, t1, q_, v_, q1_, v1_, l1_, reason)) {
      stats_.wall_seconds += seconds_since(wall0);
      throw IntegrationError(
          t1, reason + " (step " + std::to_string(stats_.steps + 1) + ", h = " + std::to_string(h_) + " s)");
    }
    if (++stats_.steps > max_steps_) throw IntegrationError(t1, "more than " + std::to_string(max_steps_) + " steps");
    deliver_up_to(t1);
    q_.swap(q1_);
    v_.swap(v1_);
    lambda_ = l1_;
    t_ = t1;
  }
  stats_.wall_seconds += seconds_since(wall0);
  return t_;
}

}  // namespace isochor
