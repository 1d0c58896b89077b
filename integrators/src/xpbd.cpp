#include "isochor/integrators/xpbd.hpp"
#include "isochor/integrators/fixed_step.hpp"

#include <algorithm>
#include <cmath>

namespace isochor {

Xpbd::Xpbd(ProjectiveSystem& system, XpbdOptions options) : sys_(system), opt_(options) {}

RunStats Xpbd::run(const std::vector<double>& times, const FrameCallback& on_frame) {
  RunStats stats;
  const Eigen::VectorXd& w = sys_.inverse_mass();
  const int P = sys_.num_points(), C = sys_.num_constraints();
  Eigen::VectorXd x0, v0, a, x_prev, lambda(C);
  sys_.initial_state(times.front(), x0, v0);
  std::vector<int> pts;
  std::vector<double> grad;
  const double h = opt_.dt / opt_.substeps;
  auto step = [&](double t, double, const VectorXd& xs, const VectorXd& vs, VectorXd& x, VectorXd& v, VectorXd&,
                  std::string& reason) {
    x = xs;
    v = vs;
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
            denom += w[pts[p]] * (grad[3 * p] * grad[3 * p] + grad[3 * p + 1] * grad[3 * p + 1] +
                                  grad[3 * p + 2] * grad[3 * p + 2]);
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
        reason = "XPBD produced a non-finite state in substep " + std::to_string(s + 1);
        return false;
      }
    }
    return true;
  };
  auto sample = [&]() { return RunStats::FrameSample{stats.steps, stats.newton_iterations, 0, 0, 0, 1, opt_.dt}; };
  run_fixed_steps(times, opt_.dt, opt_.max_steps, x0, v0, VectorXd(), step, stats, sample, on_frame);
  return stats;
}

}  // namespace isochor
