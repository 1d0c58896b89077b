#include "isochor/hong_step.hpp"

#include "isochor/fixed_step.hpp"

namespace isochor {

HongStep::HongStep(ConstrainedSystem& system, HongOptions options) : sys_(system), opt_(std::move(options)) {}

RunStats HongStep::run(const std::vector<double>& times, const FrameCallback& on_frame) {
  RunStats stats;
  const Index n = sys_.num_dofs(), m = sys_.num_constraints();
  if (m > 1) throw IntegrationError(times.front(), "Hong's step enforces one constraint, this system has " + std::to_string(m));
  const int group = sys_.dofs_per_group();
  VectorXd w = VectorXd::Ones(n);
  if (opt_.weights.size())
    for (Index i = 0; i < n; ++i) w[i] = opt_.weights[i / group];
  const VectorXd& M = sys_.mass();
  const double h = opt_.dt;
  VectorXd q0, v0, f(n), g(m), gt(m), Gf = VectorXd::Zero(n);
  std::vector<std::vector<double>> G(m);
  if (m) G[0].resize(sys_.constraint_rows()[0].size());
  sys_.initial_state(times.front(), q0, v0);
  auto step = [&](double t, double, const VectorXd& q, const VectorXd& v, VectorXd& q1, VectorXd& v1, VectorXd& l1,
                  std::string& reason) {
    sys_.force(t, q, v, f);
    stats.residual_evals++;
    v1 = v + h * f.cwiseQuotient(M);
    l1.resize(m);
    if (m) {
      sys_.constraint(t, q, g);
      sys_.constraint_jacobian(t, q, G, &gt);
      const auto& rows = sys_.constraint_rows()[0];
      double a = 0, b = g[0] / (h * h) + gt[0] / h;
      for (std::size_t k = 0; k < rows.size(); ++k) {
        const Index d = rows[k];
        a += G[0][k] * w[d] * G[0][k] / M[d];
        b += G[0][k] * (v[d] / h + f[d] / M[d]);
      }
      l1[0] = b / a;
      for (std::size_t k = 0; k < rows.size(); ++k) v1[rows[k]] -= h * w[rows[k]] * G[0][k] * l1[0] / M[rows[k]];
    }
    q1 = q + h * v1;
    if (!q1.allFinite()) {
      reason = "the mass-spring step produced a non-finite state (the step is too large for the springs)";
      return false;
    }
    return true;
  };
  auto sample = [&]() { return RunStats::FrameSample{stats.steps, 0, 0, 0, 0, 1, h}; };
  run_fixed_steps(times, h, opt_.max_steps, q0, v0, VectorXd::Zero(m), step, stats, sample, on_frame);
  return stats;
}

}  // namespace isochor
