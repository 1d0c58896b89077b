#include "isochor/integrators/xpbd.hpp"
#include "isochor/integrators/fixed_step.hpp"

#include <algorithm>
#include <cmath>

namespace isochor {

Xpbd::Xpbd(ProjectiveSystem& system, XpbdOptions options) : sys_(system), opt_(options) {}
Xpbd::~Xpbd() = default;

RunStats Xpbd::run(const std::vector<double>& times, const FrameCallback& on_frame) {
  begin(times, on_frame);
  step(times.back());
  return finish();
}

// One step of opt_.substeps substeps from t: (x, v) in, the step's end out.
bool Xpbd::substeps(double t, VectorXd& x, VectorXd& v, std::string& reason) {
  const Eigen::VectorXd& w = sys_.inverse_mass();
  const int P = sys_.num_points(), C = sys_.num_constraints();
  const double h = opt_.dt / opt_.substeps;
  for (int s = 0; s < opt_.substeps; ++s) {
    const double ts = t + (s + 1) * h;
    x_prev_ = x;
    sys_.external_acceleration(ts, a_);
    for (int i = 0; i < P; ++i)
      if (w[i] > 0) {
        v.segment<3>(3 * i) += h * a_.segment<3>(3 * i);
        x.segment<3>(3 * i) += h * v.segment<3>(3 * i);
      }
    sys_.prescribe(ts, x, v);
    lambda_.setZero(C);
    for (int it = 0; it < opt_.iterations; ++it) {
      for (int c = 0; c < C; ++c) {
        const double value = sys_.constraint(c, x, pts_, grad_);
        const double at = sys_.compliance(c) / (h * h);
        double denom = at;
        for (std::size_t p = 0; p < pts_.size(); ++p)
          denom += w[pts_[p]] * (grad_[3 * p] * grad_[3 * p] + grad_[3 * p + 1] * grad_[3 * p + 1] +
                                 grad_[3 * p + 2] * grad_[3 * p + 2]);
        if (denom <= 0 || !std::isfinite(value)) continue;  // all points fixed, or a degenerate element
        const double dl = (-value - at * lambda_[c]) / denom;
        lambda_[c] += dl;
        for (std::size_t p = 0; p < pts_.size(); ++p)
          for (int d = 0; d < 3; ++d) x[3 * pts_[p] + d] += w[pts_[p]] * grad_[3 * p + d] * dl;
      }
      sys_.after_sweep(h, x);
      stats_.newton_iterations++;  // sweeps, reported as iterations
    }
    sys_.project_collisions(ts, x);
    for (int i = 0; i < P; ++i)
      if (w[i] > 0) v.segment<3>(3 * i) = (x.segment<3>(3 * i) - x_prev_.segment<3>(3 * i)) / h;
    if (!x.allFinite()) {
      reason = "XPBD produced a non-finite state in substep " + std::to_string(s + 1);
      return false;
    }
  }
  return true;
}

void Xpbd::begin(const std::vector<double>& times, const FrameCallback& on_frame) {
  stats_ = RunStats();
  Eigen::VectorXd x0, v0;
  sys_.initial_state(times.front(), x0, v0);
  auto step = [this](double t, double, const VectorXd& xs, const VectorXd& vs, VectorXd& x, VectorXd& v, VectorXd&,
                     std::string& reason) {
    x = xs;
    v = vs;
    return substeps(t, x, v, reason);
  };
  auto sample = [this]() { return RunStats::FrameSample{stats_.steps, stats_.newton_iterations, 0, 0, 0, 1, opt_.dt}; };
  stepper_ = std::make_unique<FixedStepper>(times, opt_.dt, opt_.max_steps, step, stats_, sample, on_frame);
  stepper_->begin(x0, v0, VectorXd());
}

double Xpbd::step(double t_out) {
  if (!stepper_) throw Error("Xpbd::step before begin");
  return stepper_->step(t_out);
}

RunStats Xpbd::finish() {
  stepper_.reset();
  return stats_;
}

}  // namespace isochor
