#include "isochor/xpbd.hpp"
#include "timing.hpp"

#include <algorithm>
#include <cmath>

namespace isochor {

Xpbd::Xpbd(ProjectiveSystem& system, XpbdOptions options) : sys_(system), opt_(options) {}

IdaStats Xpbd::run(const std::vector<double>& times, const FrameCallback& on_frame) {
  IdaStats stats;
  const auto wall0 = Clock::now();
  const Eigen::VectorXd& w = sys_.inverse_mass();
  const int P = sys_.num_points(), C = sys_.num_constraints();
  Eigen::VectorXd x, v, a, x_prev, lambda(C), x1, v1;
  sys_.initial_state(times.front(), x, v);
  std::vector<int> pts;
  std::vector<double> grad;
  double t = times.front();
  const double h = opt_.dt / opt_.substeps;
  long steps = 0;
  std::size_t k = 0;
  const VectorXd none;
  auto sample = [&]() {
    stats.steps = steps;
    stats.frames.push_back({steps, stats.newton_iterations, 0, 0, 0, 1, opt_.dt});
    return stats.frames.back();
  };
  while (k < times.size() && times[k] <= t + 1e-12 * opt_.dt) {
    on_frame(static_cast<int>(k), times[k], x, v, none, sample());
    ++k;
  }
  while (k < times.size()) {
    const Eigen::VectorXd x_step = x, v_step = v;
    for (int s = 0; s < opt_.substeps; ++s) {
      const double ts = t + (s + 1) * h;
      x_prev = x;
      sys_.external_acceleration(ts, a);
      for (int i = 0; i < P; ++i)
        if (w[i] > 0) {
          v.segment<3>(3 * i) += h * a.segment<3>(3 * i);
          x.segment<3>(3 * i) += h * v.segment<3>(3 * i);
        }
      sys_.prescribe(ts, x, v);
      lambda.setZero();
      for (int it = 0; it < opt_.iterations; ++it) {
        for (int c = 0; c < C; ++c) {
          const double value = sys_.constraint(c, x, pts, grad);
          const double at = sys_.compliance(c) / (h * h);
          double denom = at;
          for (std::size_t p = 0; p < pts.size(); ++p)
            denom += w[pts[p]] * (grad[3 * p] * grad[3 * p] + grad[3 * p + 1] * grad[3 * p + 1] + grad[3 * p + 2] * grad[3 * p + 2]);
          if (denom <= 0 || !std::isfinite(value)) continue;  // all points fixed, or a degenerate element
          const double dl = (-value - at * lambda[c]) / denom;
          lambda[c] += dl;
          for (std::size_t p = 0; p < pts.size(); ++p)
            for (int d = 0; d < 3; ++d) x[3 * pts[p] + d] += w[pts[p]] * grad[3 * p + d] * dl;
        }
        sys_.after_sweep(h, x);
        stats.newton_iterations++;  // sweeps, reported as iterations
      }
      sys_.project_collisions(ts, x);
      for (int i = 0; i < P; ++i)
        if (w[i] > 0) v.segment<3>(3 * i) = (x.segment<3>(3 * i) - x_prev.segment<3>(3 * i)) / h;
      if (!x.allFinite()) {
        stats.wall_seconds = seconds_since(wall0);
        throw IntegrationError(ts, "XPBD produced a non-finite state (substep " + std::to_string(s + 1) + " of step " +
                                       std::to_string(steps + 1) + ")");
      }
    }
    const double t1 = t + opt_.dt;
    ++steps;
    if (steps > opt_.max_steps) throw IntegrationError(t1, "more than " + std::to_string(opt_.max_steps) + " steps");
    while (k < times.size() && times[k] <= t1 + 1e-9 * opt_.dt) {
      const double s = std::clamp((times[k] - t) / opt_.dt, 0.0, 1.0);
      x1 = (1 - s) * x_step + s * x;
      v1 = (1 - s) * v_step + s * v;
      on_frame(static_cast<int>(k), times[k], x1, v1, none, sample());
      ++k;
    }
    t = t1;
  }
  stats.steps = steps;
  stats.wall_seconds = seconds_since(wall0);
  return stats;
}

}  // namespace isochor
