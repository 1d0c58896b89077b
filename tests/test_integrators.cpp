// Every integrator through the ConstrainedSystem interface on small DAEs that are not meshes: a
// chain of particles in the plane (dofs in groups of 2), each link a length constraint. Checked
// against independent solutions in angle coordinates (RK4), closed-form equilibria, and the
// convergence order of backward Euler.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "isochor/integrators/sparse_factor.hpp"
#include "isochor/integrators/backward_euler.hpp"
#include "isochor/integrators/ida_integrator.hpp"
#include "isochor/integrators/statics.hpp"

#include "test_util.hpp"

using namespace isochor;

namespace {

constexpr double kG = 9.81, kMass = 1.5;

// Particles 0..P-1 in the plane, link j of length L_j from particle j-1 (the origin for j = 0) to
// particle j: g_j = (|q_j - q_{j-1}|^2 - L_j^2) / 2. Gravity -g y on every particle.
class Chain : public ConstrainedSystem {
 public:
  Chain(std::vector<double> lengths, std::vector<double> angles, int group = 2)
      : L_(std::move(lengths)), theta0_(std::move(angles)), group_(group) {
    const int P = static_cast<int>(L_.size());
    n_ = 2 * P;
    mass_ = VectorXd::Constant(n_, kMass);
    pattern_.n = n_;  // dense: a handful of dofs
    for (Index c = 0; c <= n_; ++c) pattern_.col_ptr.push_back(c * n_);
    for (Index c = 0; c < n_; ++c)
      for (Index r = 0; r < n_; ++r) pattern_.row_ind.push_back(r);
    for (int j = 0; j < P; ++j) {
      std::vector<Index> row;
      if (j > 0) row = {2 * (j - 1), 2 * (j - 1) + 1};
      row.push_back(2 * j);
      row.push_back(2 * j + 1);
      rows_.push_back(row);
    }
  }
  int num_dofs() const override { return static_cast<int>(n_); }
  int num_constraints() const override { return static_cast<int>(L_.size()); }
  int dofs_per_group() const override { return group_; }
  const VectorXd& mass() const override { return mass_; }
  const SparsePattern& pattern() const override { return pattern_; }
  const std::vector<std::vector<Index>>& constraint_rows() const override { return rows_; }
  void initial_state(double, VectorXd& q, VectorXd& v) override {
    q.resize(n_);
    v.setZero(n_);
    Eigen::Vector2d p(0, 0);
    for (std::size_t j = 0; j < L_.size(); ++j) {
      p += L_[j] * Eigen::Vector2d(std::sin(theta0_[j]), -std::cos(theta0_[j]));
      q.segment<2>(2 * j) = p;
    }
  }
  void force(double, const VectorXd& q, const VectorXd&, VectorXd& f) override {
    f.setZero(n_);
    for (Index i = 0; i < n_; i += 2) f[i + 1] = -kMass * kG;
    if (anchor.size()) f -= k_anchor * (q - anchor);
  }
  void add_force_jacobians(double, const VectorXd&, const VectorXd&, double* neg_dfdq, double*) override {
    if (neg_dfdq && anchor.size())
      for (Index i = 0; i < n_; ++i) neg_dfdq[i * n_ + i] += k_anchor;
  }
  // Springs of stiffness k_anchor pulling the particles towards `anchor` (none if empty).
  VectorXd anchor;
  double k_anchor = 0;
  Eigen::Vector2d link(const VectorXd& q, int j) const {
    return j == 0 ? Eigen::Vector2d(q.segment<2>(0)) : Eigen::Vector2d(q.segment<2>(2 * j) - q.segment<2>(2 * j - 2));
  }
  void constraint(double, const VectorXd& q, VectorXd& g) override {
    g.resize(num_constraints());
    for (int j = 0; j < num_constraints(); ++j) g[j] = 0.5 * (link(q, j).squaredNorm() - L_[j] * L_[j]);
  }
  void constraint_jacobian(double, const VectorXd& q, std::vector<std::vector<double>>& G, VectorXd* gt) override {
    for (int j = 0; j < num_constraints(); ++j) {
      const Eigen::Vector2d d = link(q, j);
      G[j] = j == 0 ? std::vector<double>{d[0], d[1]} : std::vector<double>{-d[0], -d[1], d[0], d[1]};
    }
    if (gt) gt->setZero(num_constraints());
  }
  void add_constraint_hessian(double, const VectorXd&, const VectorXd& w, double scale, double* values) override {
    // H_j = [I -I; -I I] over (particle j-1, particle j); [I] alone for j = 0.
    for (int j = 0; j < num_constraints(); ++j)
      for (int d = 0; d < 2; ++d) {
        const Index b = 2 * j + d;
        values[b * n_ + b] += scale * w[j];
        if (j == 0) continue;
        const Index a = 2 * (j - 1) + d;
        values[a * n_ + a] += scale * w[j];
        values[a * n_ + b] -= scale * w[j];
        values[b * n_ + a] -= scale * w[j];
      }
  }
  void constraint_velocity_jacobian(double, const VectorXd&, const VectorXd& v,
                                    std::vector<std::vector<double>>& rows) override {
    for (int j = 0; j < num_constraints(); ++j) {
      const Eigen::Vector2d d = link(v, j);
      rows[j] = j == 0 ? std::vector<double>{d[0], d[1]} : std::vector<double>{-d[0], -d[1], d[0], d[1]};
    }
  }
  double force_scale() const override { return kMass * kG; }
  double constraint_scale(int j) const override { return L_[j] * L_[j]; }

 private:
  std::vector<double> L_, theta0_;
  int group_;
  Index n_ = 0;
  VectorXd mass_;
  SparsePattern pattern_;
  std::vector<std::vector<Index>> rows_;
};

// The chain of one or two links in angle coordinates (from the downward vertical), equal masses,
// started at rest, integrated by RK4 at 1e-5 s; positions of every particle at `times`.
std::vector<VectorXd> reference(const std::vector<double>& L, const std::vector<double>& th0,
                                const std::vector<double>& times) {
  const int P = static_cast<int>(L.size());
  Eigen::Vector4d y(th0[0], P > 1 ? th0[1] : 0.0, 0, 0);  // theta1, theta2, omega1, omega2
  auto rhs = [&](const Eigen::Vector4d& s) {
    Eigen::Vector4d d(s[2], s[3], 0, 0);
    if (P == 1) {
      d[2] = -kG / L[0] * std::sin(s[0]);
    } else {  // equal masses m1 = m2: the double pendulum's equations of motion
      const double a = s[0], b = s[1], wa = s[2], wb = s[3], den = 3.0 - std::cos(2 * a - 2 * b);
      d[2] = (-3 * kG * std::sin(a) - kG * std::sin(a - 2 * b) -
              2 * std::sin(a - b) * (wb * wb * L[1] + wa * wa * L[0] * std::cos(a - b))) /
             (L[0] * den);
      d[3] = 2 * std::sin(a - b) * (wa * wa * L[0] * 2 + 2 * kG * std::cos(a) + wb * wb * L[1] * std::cos(a - b)) /
             (L[1] * den);
    }
    return d;
  };
  std::vector<VectorXd> out;
  double t = 0;
  for (double tf : times) {
    while (t < tf - 1e-12) {
      const double h = std::min(1e-5, tf - t);
      const Eigen::Vector4d k1 = rhs(y), k2 = rhs(y + 0.5 * h * k1), k3 = rhs(y + 0.5 * h * k2), k4 = rhs(y + h * k3);
      y += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
      t += h;
    }
    VectorXd q(2 * P);
    Eigen::Vector2d p(0, 0);
    for (int j = 0; j < P; ++j) {
      p += L[j] * Eigen::Vector2d(std::sin(y[j]), -std::cos(y[j]));
      q.segment<2>(2 * j) = p;
    }
    out.push_back(q);
  }
  return out;
}

// Largest position error over the frames.
double worst_error(Integrator& integrator, const std::vector<double>& times, const std::vector<VectorXd>& ref) {
  double worst = 0;
  integrator.run(times,
                 [&](int k, double, const VectorXd& q, const VectorXd&, const VectorXd&, const RunStats::FrameSample&) {
                   worst = std::max(worst, (q - ref[k]).cwiseAbs().maxCoeff());
                 });
  return worst;
}

const std::vector<double> kDoubleL = {1.0, 0.7}, kDoubleTheta = {1.0, -0.5};

}  // namespace

TEST(Integrators, DofsNotAMultipleOfTheGroupSizeAreRejectedWhereGroupsOrderTheSolve) {
  // A 2-D pendulum (n = 2) that keeps the default group of 3 dofs. The solvers that order the
  // dofs by groups (METIS's node ordering: KLU in IDA and statics, backward Euler's KKT matrix)
  // refuse it with a message naming themselves instead of reading past the end of the ordering
  // (it crashed in METIS's); the others never group the dofs and run it.
  auto message = [](auto&& make) {
    try {
      make();
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  IdaOptions klu_metis;
  BackwardEulerOptions be_klu;
  be_klu.linear_solver = LinearSolverKind::klu;
  StaticOptions statics_klu;
  statics_klu.linear_solver = LinearSolverKind::klu;
  const std::string refused[] = {message([&] {
                                   Chain c({1.0}, {0.5}, 3);
                                   IdaIntegrator i(c, klu_metis);
                                 }),
                                 message([&] {
                                   Chain c({1.0}, {0.5}, 3);
                                   BackwardEuler i(c, be_klu);
                                 }),
                                 message([&] {
                                   Chain c({1.0}, {0.5}, 3);
                                   StaticSolver i(c, statics_klu);
                                 })};
  for (const std::string& m : refused) {
    EXPECT_NE(m.find("orders the dofs by groups of dofs_per_group() = 3, but the system has 2 dofs"), std::string::npos)
        << m;
  }
  EXPECT_NE(refused[0].find("METIS"), std::string::npos) << refused[0];
  EXPECT_NE(refused[1].find("KKT"), std::string::npos) << refused[1];
  // The same pendulum with groups of 2 as the reference: the ungrouped solvers give its motion.
  const auto times = test::frame_times(0.5, 0.5);
  auto last_q = [&](int group, auto&& make) {
    Chain c({1.0}, {0.5}, group);
    auto integ = make(c);
    VectorXd last;
    integ->run(times, [&](int, double, const VectorXd& q, const VectorXd&, const VectorXd&,
                          const RunStats::FrameSample&) { last = q; });
    return last;
  };
  for (LinearSolverKind ls : {LinearSolverKind::klu, LinearSolverKind::reduced, LinearSolverKind::krylov}) {
    for (KluOrdering ord : {KluOrdering::amd, KluOrdering::colamd}) {
      if (ls != LinearSolverKind::klu && ord == KluOrdering::colamd) continue;
      auto ida = [&](Chain& c) {
        IdaOptions o;
        o.linear_solver = ls;
        o.ordering = ord;
        return std::make_unique<IdaIntegrator>(c, o);
      };
      const VectorXd with3 = last_q(3, ida), with2 = last_q(2, ida);
      EXPECT_LT((with3 - with2).norm(), 1e-12) << to_string(ls);
    }
  }
  auto be = [](Chain& c) { return std::make_unique<BackwardEuler>(c, BackwardEulerOptions{}); };
  EXPECT_LT((last_q(3, be) - last_q(2, be)).norm(), 1e-12);
}

namespace {
// Every linear solver this build has (amg: with hypre).
std::vector<LinearSolverKind> every_linear_solver() {
  std::vector<LinearSolverKind> k{LinearSolverKind::klu, LinearSolverKind::reduced, LinearSolverKind::krylov};
  if (amg_available()) k.push_back(LinearSolverKind::amg);
  return k;
}
}  // namespace

TEST(Integrators, IdaFollowsTheDoublePendulumWithEveryLinearSolver) {
  // Groups of 2 dofs: KLU's METIS order over the particles, the reduced and krylov solvers.
  const auto times = test::frame_times(1.0, 0.02);
  const auto ref = reference(kDoubleL, kDoubleTheta, times);
  for (LinearSolverKind ls : every_linear_solver()) {
    Chain c(kDoubleL, kDoubleTheta);
    IdaOptions o;
    o.rtol = o.atol_q = o.atol_v = 1e-9;
    o.linear_solver = ls;
    IdaIntegrator ida(c, o);
    const double e = worst_error(ida, times, ref);
    EXPECT_LT(e, 1e-5) << to_string(ls);
    std::printf("IDA %s: double pendulum max error %.2e m\n", to_string(ls), e);
  }
}

TEST(Integrators, StaticsFindsTheHangingDoublePendulumAndItsTensions) {
  // Hanging straight down: q1 = (0, -L1), q2 = (0, -L1 - L2). With M v' = f - G^T lambda (the
  // sign convention of constrained_system.hpp) and G_j = (q_j - q_{j-1})^T: particle 2 gives
  // lambda_2 = m g / L2, particle 1 lambda_1 = 2 m g / L1 (link tensions over their lengths).
  // Springs anchored at the hanging positions (no force there, so the tensions do not change)
  // make the stiffness regular: without them it is zero, and so is the reduced solver's block.
  for (LinearSolverKind ls : every_linear_solver()) {
    Chain c(kDoubleL, {0.3, -0.2});
    c.anchor = Eigen::Vector4d(0, -kDoubleL[0], 0, -kDoubleL[0] - kDoubleL[1]);
    c.k_anchor = 10.0;
    StaticOptions o;
    o.linear_solver = ls;
    StaticSolver s(c, o);
    VectorXd q, lambda;
    s.run({0.0},
          [&](int, double, const VectorXd& qq, const VectorXd&, const VectorXd& l, const RunStats::FrameSample&) {
            q = qq;
            lambda = l;
          });
    ASSERT_EQ(q.size(), 4);
    EXPECT_NEAR(q[0], 0.0, 1e-9) << to_string(ls);
    EXPECT_NEAR(q[1], -kDoubleL[0], 1e-9);
    EXPECT_NEAR(q[2], 0.0, 1e-9);
    EXPECT_NEAR(q[3], -kDoubleL[0] - kDoubleL[1], 1e-9);
    EXPECT_NEAR(lambda[0], 2 * kMass * kG / kDoubleL[0], 1e-6);
    EXPECT_NEAR(lambda[1], kMass * kG / kDoubleL[1], 1e-6);
  }
}

TEST(Integrators, BackwardEulerConvergesAtFirstOrderWithEveryLinearSolver) {
  // The pendulum over 0.5 s at h = 1e-2 ... 1e-5: the error must fall ten times per decade of h
  // (first order) down to the smallest step, with every linear solver. Newton's tolerance is
  // relative to the step's displacement, so it never caps the accuracy at small h (it did when
  // it was an absolute 1e-8 m with KLU's reused factorisation: worse at 1e-5 than at 1e-4).
  const std::vector<double> times = {0.0, 0.1, 0.2, 0.3, 0.4, 0.5};
  const auto ref = reference({1.0}, {1.0}, times);
  for (LinearSolverKind ls : every_linear_solver()) {
    std::vector<double> errors;
    for (double h : {1e-2, 1e-3, 1e-4, 1e-5}) {
      Chain c({1.0}, {1.0});
      BackwardEulerOptions o;
      o.dt = h;
      o.linear_solver = ls;
      BackwardEuler be(c, o);
      errors.push_back(worst_error(be, times, ref));
    }
    std::printf("backward Euler %s: errors %.3e %.3e %.3e %.3e\n", to_string(ls), errors[0], errors[1], errors[2],
                errors[3]);
    for (std::size_t i = 1; i < errors.size(); ++i) {
      const double ratio = errors[i - 1] / errors[i];
      EXPECT_GT(ratio, 7.0) << to_string(ls) << " h = " << std::pow(10.0, -1.0 - i);
      EXPECT_LT(ratio, 14.0) << to_string(ls) << " h = " << std::pow(10.0, -1.0 - i);
    }
  }
}

TEST(Integrators, BackwardEulerStepsEndOnMultiplesOfTheStep) {
  // 1e5 steps of 1e-5 on [0, 1]: the last frame at exactly t = 1 after exactly 1e5 steps (time is
  // t0 + k h, not accumulated; accumulated, it took 100,001).
  Chain c({1.0}, {0.2});
  BackwardEulerOptions o;
  o.dt = 1e-5;
  BackwardEuler be(c, o);
  const RunStats s = be.run(
      {0.0, 1.0}, [](int, double, const VectorXd&, const VectorXd&, const VectorXd&, const RunStats::FrameSample&) {});
  EXPECT_EQ(s.steps, 100000);
}
