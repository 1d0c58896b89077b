#include "isochor/integrators/hong_step.hpp"

#include "isochor/integrators/fixed_step.hpp"
#include "isochor/integrators/initial_state.hpp"

#include <Eigen/LU>

namespace isochor {

// Hong's per-dof weights and what a step reuses.
struct HongStep::Work {
  VectorXd w, f, g, gt, c, b;
  Eigen::MatrixXd A;
  std::vector<std::vector<double>> G;
  // Row k's velocity correction is -h W_k M^-1 G_k^T l_k, W_k Hong's weights for the first
  // weighted_rows rows (the enclosed volume), 1 for the rest (supports).
  double weight(Index k, Index d, const HongOptions& o) const { return k < o.weighted_rows ? w[d] : 1.0; }
};

HongStep::HongStep(ConstrainedSystem& system, HongOptions options) : sys_(system), opt_(std::move(options)) {}
HongStep::~HongStep() = default;

RunStats HongStep::run(const std::vector<double>& times, const FrameCallback& on_frame) {
  begin(times, on_frame);
  step(times.back());
  return finish();
}

bool HongStep::one_step(Work& k, double t, const VectorXd& q, const VectorXd& v, VectorXd& q1, VectorXd& v1,
                        VectorXd& l1, std::string& reason) {
  const Index m = sys_.num_constraints();
  const VectorXd& M = sys_.mass();
  const auto& rows = sys_.constraint_rows();
  const double h = opt_.dt;
  sys_.force(t, q, v, k.f);
  stats_.residual_evals++;
  v1 = v + h * k.f.cwiseQuotient(M);
  l1.resize(m);
  if (m) {
    // Every row holds after the step to first order: G (q + h v1) + g = 0 with g_t, i.e.
    // sum_k (G_j W_k M^-1 G_k^T) l_k = g_j / h^2 + g_t,j / h + G_j (v / h + M^-1 f).
    sys_.constraint(t, q, k.g);
    sys_.constraint_jacobian(t, q, k.G, &k.gt);
    for (Index j = 0; j < m; ++j) {
      k.b[j] = k.g[j] / (h * h) + k.gt[j] / h;
      for (std::size_t i = 0; i < rows[j].size(); ++i)
        k.b[j] += k.G[j][i] * (v[rows[j][i]] / h + k.f[rows[j][i]] / M[rows[j][i]]);
    }
    for (Index r = 0; r < m; ++r) {
      for (std::size_t i = 0; i < rows[r].size(); ++i)
        k.c[rows[r][i]] = k.weight(r, rows[r][i], opt_) * k.G[r][i] / M[rows[r][i]];
      for (Index j = 0; j < m; ++j) {
        double s = 0;
        for (std::size_t i = 0; i < rows[j].size(); ++i) s += k.G[j][i] * k.c[rows[j][i]];
        k.A(j, r) = s;
      }
      for (Index d : rows[r]) k.c[d] = 0;
    }
    l1 = m == 1 ? VectorXd(k.b / k.A(0, 0)) : VectorXd(k.A.partialPivLu().solve(k.b));
    for (Index r = 0; r < m; ++r)
      for (std::size_t i = 0; i < rows[r].size(); ++i)
        v1[rows[r][i]] -= h * k.weight(r, rows[r][i], opt_) * k.G[r][i] * l1[r] / M[rows[r][i]];
  }
  q1 = q + h * v1;
  if (!q1.allFinite()) {
    reason = "the mass-spring step produced a non-finite state (the step is too large for the springs)";
    return false;
  }
  return true;
}

void HongStep::begin(const std::vector<double>& times, const FrameCallback& on_frame) {
  stats_ = RunStats();
  const Index n = sys_.num_dofs(), m = sys_.num_constraints();
  const int group = sys_.dofs_per_group();
  work_ = std::make_unique<Work>();
  Work& k = *work_;
  k.w = VectorXd::Ones(n);
  if (opt_.weights.size()) {
    check_groups(sys_, "Hong's per-node weights");
    for (Index i = 0; i < n; ++i) k.w[i] = opt_.weights[i / group];
  }
  k.f.resize(n);
  k.g.resize(m);
  k.gt.resize(m);
  k.c = VectorXd::Zero(n);
  k.A.resize(m, m);
  k.b.resize(m);
  k.G.resize(m);
  for (Index j = 0; j < m; ++j) k.G[j].resize(sys_.constraint_rows()[j].size());
  VectorXd q0, v0;
  sys_.initial_state(times.front(), q0, v0);
  auto step = [this](double t, double, const VectorXd& q, const VectorXd& v, VectorXd& q1, VectorXd& v1, VectorXd& l1,
                     std::string& reason) { return one_step(*work_, t, q, v, q1, v1, l1, reason); };
  auto sample = [this]() { return RunStats::FrameSample{stats_.steps, 0, 0, 0, 0, 1, opt_.dt}; };
  stepper_ = std::make_unique<FixedStepper>(times, opt_.dt, opt_.max_steps, step, stats_, sample, on_frame);
  stepper_->begin(q0, v0, VectorXd::Zero(m));
}

double HongStep::step(double t_out) {
  if (!stepper_) throw Error("HongStep::step before begin");
  return stepper_->step(t_out);
}

RunStats HongStep::finish() {
  stepper_.reset();
  work_.reset();
  return stats_;
}

}  // namespace isochor
