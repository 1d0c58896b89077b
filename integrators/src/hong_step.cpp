#include "isochor/integrators/hong_step.hpp"

#include "isochor/integrators/fixed_step.hpp"
#include "isochor/integrators/initial_state.hpp"

#include <Eigen/LU>

namespace isochor {

HongStep::HongStep(ConstrainedSystem& system, HongOptions options) : sys_(system), opt_(std::move(options)) {}

RunStats HongStep::run(const std::vector<double>& times, const FrameCallback& on_frame) {
  RunStats stats;
  const Index n = sys_.num_dofs(), m = sys_.num_constraints();
  const int group = sys_.dofs_per_group();
  VectorXd w = VectorXd::Ones(n);
  if (opt_.weights.size()) {
    check_groups(sys_, "Hong's per-node weights");
    for (Index i = 0; i < n; ++i) w[i] = opt_.weights[i / group];
  }
  const VectorXd& M = sys_.mass();
  const double h = opt_.dt;
  const auto& rows = sys_.constraint_rows();
  VectorXd q0, v0, f(n), g(m), gt(m), c = VectorXd::Zero(n);
  Eigen::MatrixXd A(m, m);
  VectorXd b(m);
  std::vector<std::vector<double>> G(m);
  for (Index j = 0; j < m; ++j) G[j].resize(rows[j].size());
  sys_.initial_state(times.front(), q0, v0);
  // Row k's velocity correction is -h W_k M^-1 G_k^T l_k, W_k Hong's weights for the first
  // weighted_rows rows (the enclosed volume), 1 for the rest (supports).
  auto weight = [&](Index k, Index d) { return k < opt_.weighted_rows ? w[d] : 1.0; };
  auto step = [&](double t, double, const VectorXd& q, const VectorXd& v, VectorXd& q1, VectorXd& v1, VectorXd& l1,
                  std::string& reason) {
    sys_.force(t, q, v, f);
    stats.residual_evals++;
    v1 = v + h * f.cwiseQuotient(M);
    l1.resize(m);
    if (m) {
      // Every row holds after the step to first order: G (q + h v1) + g = 0 with g_t, i.e.
      // sum_k (G_j W_k M^-1 G_k^T) l_k = g_j / h^2 + g_t,j / h + G_j (v / h + M^-1 f).
      sys_.constraint(t, q, g);
      sys_.constraint_jacobian(t, q, G, &gt);
      for (Index j = 0; j < m; ++j) {
        b[j] = g[j] / (h * h) + gt[j] / h;
        for (std::size_t k = 0; k < rows[j].size(); ++k)
          b[j] += G[j][k] * (v[rows[j][k]] / h + f[rows[j][k]] / M[rows[j][k]]);
      }
      for (Index k = 0; k < m; ++k) {
        for (std::size_t i = 0; i < rows[k].size(); ++i)
          c[rows[k][i]] = weight(k, rows[k][i]) * G[k][i] / M[rows[k][i]];
        for (Index j = 0; j < m; ++j) {
          double s = 0;
          for (std::size_t i = 0; i < rows[j].size(); ++i) s += G[j][i] * c[rows[j][i]];
          A(j, k) = s;
        }
        for (Index d : rows[k]) c[d] = 0;
      }
      l1 = m == 1 ? VectorXd(b / A(0, 0)) : VectorXd(A.partialPivLu().solve(b));
      for (Index k = 0; k < m; ++k)
        for (std::size_t i = 0; i < rows[k].size(); ++i)
          v1[rows[k][i]] -= h * weight(k, rows[k][i]) * G[k][i] * l1[k] / M[rows[k][i]];
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
