// Two index-3 DAEs of the standard test sets, written through the public ConstrainedSystem
// interface, with their published reference solutions: the accuracy of every integrator and
// linear solver is measured on them (tests/test_dae_accuracy.cpp, bench/dae_accuracy.cpp).
//
// - The pendulum of the MEBDFDAE test set (Cash): unit mass and length, force (0, -1),
//   g = x^2 + y^2 - 1, q(0) = (1, 0), v(0) = (0, 1), t in [0, 1].
// - The car axis of the IVP test set (Mazzia & Magherini, problem "caraxis"): two wheels of mass
//   M eps^2 / 2 on springs, an axis of length L between them, the left wheel held on a moving
//   circle; t in [0, 3].
//
// The car axis's test set writes M v' = f + G^T lambda; this interface writes
// M v' = f - G^T lambda, so its multipliers here are minus the test set's. MEBDFDAE's pendulum
// writes v' = f - y5 q, and G = (2x, 2y) here: lambda = y5 / 2.
#pragma once
#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Dense>

#include "isochor/integrators/constrained_system.hpp"
#include "isochor/integrators/integrator.hpp"

namespace isochor::test {

// A dense n x n pattern (the problems are tiny): entry (r, c) at c n + r.
inline SparsePattern dense_pattern(Index n) {
  SparsePattern p;
  p.n = n;
  for (Index c = 0; c <= n; ++c) p.col_ptr.push_back(c * n);
  for (Index c = 0; c < n; ++c)
    for (Index r = 0; r < n; ++r) p.row_ind.push_back(r);
  return p;
}

// A test DAE: the system and its reference state at end_time (positions, velocities, multipliers
// in this interface's sign convention).
class TestDae : public ConstrainedSystem {
 public:
  virtual double end_time() const = 0;
  virtual void reference(VectorXd& q, VectorXd& v, VectorXd& lambda) const = 0;
  // The explicit time derivative of G(q, t) v + dg/dt at fixed (q, v): with
  // constraint_velocity_jacobian() it gives the acceleration-level constraint of the index-1 form.
  virtual VectorXd constraint_velocity_t(double t, const VectorXd& q, const VectorXd& v) const = 0;

  // The acceleration of the index-1 form: M a + G^T lambda = f, G a = -d/dt (G v + dg/dt) at a = 0.
  VectorXd acceleration(double t, const VectorXd& q, const VectorXd& v) {
    const Index n = num_dofs(), m = num_constraints();
    std::vector<std::vector<double>> G(m), H(m);
    for (Index j = 0; j < m; ++j) G[j].resize(constraint_rows()[j].size()), H[j].resize(G[j].size());
    constraint_jacobian(t, q, G, nullptr);
    constraint_velocity_jacobian(t, q, v, H);
    VectorXd f;
    force(t, q, v, f);
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n + m, n + m);
    VectorXd b(n + m);
    A.topLeftCorner(n, n) = mass().asDiagonal();
    b.head(n) = f;
    b.tail(m) = -constraint_velocity_t(t, q, v);
    for (Index j = 0; j < m; ++j)
      for (std::size_t k = 0; k < G[j].size(); ++k) {
        const Index d = constraint_rows()[j][k];
        A(n + j, d) = A(d, n + j) = G[j][k];
        b[n + j] -= H[j][k] * v[d];
      }
    return A.fullPivLu().solve(b).head(n);
  }
  // An independent reference along the whole run: the index-1 form integrated by the classical
  // Runge-Kutta method with step h (error O(h^4)), its state at each of `times` (increasing, from 0).
  void reference_trajectory(const std::vector<double>& times, double h, std::vector<VectorXd>& qs,
                            std::vector<VectorXd>& vs) {
    VectorXd q, v;
    initial_state(0.0, q, v);
    double t = 0;
    for (double tf : times) {
      while (t < tf - 1e-14) {
        const double k = std::min(h, tf - t);
        const VectorXd a1 = acceleration(t, q, v);
        const VectorXd q2 = q + 0.5 * k * v, v2 = v + 0.5 * k * a1;
        const VectorXd a2 = acceleration(t + 0.5 * k, q2, v2);
        const VectorXd q3 = q + 0.5 * k * v2, v3 = v + 0.5 * k * a2;
        const VectorXd a3 = acceleration(t + 0.5 * k, q3, v3);
        const VectorXd q4 = q + k * v3, v4 = v + k * a3;
        const VectorXd a4 = acceleration(t + k, q4, v4);
        q += k / 6 * (v + 2 * v2 + 2 * v3 + v4);
        v += k / 6 * (a1 + 2 * a2 + 2 * a3 + a4);
        t += k;
      }
      qs.push_back(q);
      vs.push_back(v);
    }
  }
  // The test sets' significant correct digits, -log10 of the largest relative error over the
  // positions and velocities (the differential components; the multipliers are reported apart).
  double correct_digits(const VectorXd& q, const VectorXd& v) const {
    VectorXd qr, vr, lr;
    reference(qr, vr, lr);
    double worst = 0;
    for (Index i = 0; i < qr.size(); ++i) worst = std::max(worst, std::abs(q[i] - qr[i]) / std::abs(qr[i]));
    for (Index i = 0; i < vr.size(); ++i) worst = std::max(worst, std::abs(v[i] - vr[i]) / std::abs(vr[i]));
    return -std::log10(worst);
  }
  // Correct digits along a run: -log10 of the largest error over frames and components of q and
  // v, each component's error relative to its largest size over the reference run.
  static double trajectory_digits(const std::vector<VectorXd>& q, const std::vector<VectorXd>& v,
                                  const std::vector<VectorXd>& qr, const std::vector<VectorXd>& vr) {
    const Index n = qr.front().size();
    VectorXd scale = VectorXd::Zero(2 * n);
    for (std::size_t k = 0; k < qr.size(); ++k)
      for (Index i = 0; i < n; ++i) {
        scale[i] = std::max(scale[i], std::abs(qr[k][i]));
        scale[n + i] = std::max(scale[n + i], std::abs(vr[k][i]));
      }
    double worst = 0;
    for (std::size_t k = 0; k < qr.size(); ++k)
      for (Index i = 0; i < n; ++i) {
        worst = std::max(worst, std::abs(q[k][i] - qr[k][i]) / scale[i]);
        worst = std::max(worst, std::abs(v[k][i] - vr[k][i]) / scale[n + i]);
      }
    return -std::log10(worst);
  }
  double multiplier_digits(const VectorXd& lambda) const {
    VectorXd qr, vr, lr;
    reference(qr, vr, lr);
    double worst = 0;
    for (Index i = 0; i < lr.size(); ++i) worst = std::max(worst, std::abs(lambda[i] - lr[i]) / std::abs(lr[i]));
    return -std::log10(worst);
  }
};

class MebdfPendulum : public TestDae {
 public:
  explicit MebdfPendulum(int group = 2) : group_(group), mass_(VectorXd::Ones(2)), pattern_(dense_pattern(2)) {}
  int num_dofs() const override { return 2; }
  int num_constraints() const override { return 1; }
  int dofs_per_group() const override { return group_; }
  const VectorXd& mass() const override { return mass_; }
  const SparsePattern& pattern() const override { return pattern_; }
  const std::vector<std::vector<Index>>& constraint_rows() const override { return rows_; }
  void initial_state(double, VectorXd& q, VectorXd& v) override {
    q = Eigen::Vector2d(1, 0);
    v = Eigen::Vector2d(0, 1);
  }
  void force(double, const VectorXd&, const VectorXd&, VectorXd& f) override { f = Eigen::Vector2d(0, -1); }
  void add_force_jacobians(double, const VectorXd&, const VectorXd&, double*, double*) override {}
  void constraint(double, const VectorXd& q, VectorXd& g) override {
    g.resize(1);
    g[0] = q.squaredNorm() - 1;
  }
  void constraint_jacobian(double, const VectorXd& q, std::vector<std::vector<double>>& G, VectorXd* gt) override {
    G[0] = {2 * q[0], 2 * q[1]};
    if (gt) gt->setZero(1);
  }
  void add_constraint_hessian(double, const VectorXd&, const VectorXd& w, double scale, double* values) override {
    values[0] += 2 * scale * w[0];
    values[3] += 2 * scale * w[0];
  }
  void constraint_velocity_jacobian(double, const VectorXd&, const VectorXd& v,
                                    std::vector<std::vector<double>>& rows) override {
    rows[0] = {2 * v[0], 2 * v[1]};
  }
  VectorXd constraint_velocity_t(double, const VectorXd&, const VectorXd&) const override { return VectorXd::Zero(1); }
  double end_time() const override { return 1.0; }
  // MEBDFDAE's SOLN at t = 1: y1..y4 = q, v; lambda = y5 / 2.
  void reference(VectorXd& q, VectorXd& v, VectorXd& lambda) const override {
    q = Eigen::Vector2d(0.867348640604551746, 0.497701050476373918);
    v = Eigen::Vector2d(-0.337480180329866458e-1, 0.588130114660715686e-1);
    lambda = VectorXd::Constant(1, -0.493103151528274442 / 2);
  }

 private:
  int group_;
  VectorXd mass_;
  SparsePattern pattern_;
  std::vector<std::vector<Index>> rows_{{0, 1}};
};

class CarAxis : public TestDae {
 public:
  static constexpr double kEps = 1e-2, kM = 10, kL = 1, kL0 = 0.5, kR = 0.1, kW = 10, kG = 1;
  static constexpr double kMass = kM * kEps * kEps / 2;
  // Dofs (x_l, y_l, x_r, y_r): the two wheels. Groups of 2 (a wheel's x, y) by default; 3 does not
  // divide the 4 dofs, for the tests of where that is refused.
  explicit CarAxis(int group = 2) : group_(group), mass_(VectorXd::Constant(4, kMass)), pattern_(dense_pattern(4)) {}
  int num_dofs() const override { return 4; }
  int num_constraints() const override { return 2; }
  int dofs_per_group() const override { return group_; }
  const VectorXd& mass() const override { return mass_; }
  const SparsePattern& pattern() const override { return pattern_; }
  const std::vector<std::vector<Index>>& constraint_rows() const override { return rows_; }
  void initial_state(double, VectorXd& q, VectorXd& v) override {
    q.resize(4);
    q << 0, 0.5, 1, 0.5;
    v.resize(4);
    v << -0.5, 0, -0.5, 0;
  }
  // The moving point (x_b, y_b) on the circle of radius L that holds the left wheel's direction,
  // and its velocity.
  static void axle(double t, double& xb, double& yb, double& dxb, double& dyb) {
    yb = kR * std::sin(kW * t);
    xb = std::sqrt(kL * kL - yb * yb);
    dyb = kR * kW * std::cos(kW * t);
    dxb = -yb * dyb / xb;
  }
  void force(double t, const VectorXd& q, const VectorXd&, VectorXd& f) override {
    double xb, yb, dxb, dyb;
    axle(t, xb, yb, dxb, dyb);
    f.resize(4);
    spring(q[0], q[1], f[0], f[1]);
    spring(q[2] - xb, q[3] - yb, f[2], f[3]);
    f[1] -= kMass * kG;
    f[3] -= kMass * kG;
  }
  // -df/dq of the spring L0 p / |p| - p: I - L0 (I - n n^T) / |p| per wheel.
  void add_force_jacobians(double t, const VectorXd& q, const VectorXd&, double* K, double*) override {
    if (!K) return;
    double xb, yb, dxb, dyb;
    axle(t, xb, yb, dxb, dyb);
    spring_jacobian(q[0], q[1], 0, K);
    spring_jacobian(q[2] - xb, q[3] - yb, 2, K);
  }
  void constraint(double t, const VectorXd& q, VectorXd& g) override {
    double xb, yb, dxb, dyb;
    axle(t, xb, yb, dxb, dyb);
    g.resize(2);
    g[0] = xb * q[0] + yb * q[1];
    g[1] = (q[0] - q[2]) * (q[0] - q[2]) + (q[1] - q[3]) * (q[1] - q[3]) - kL * kL;
  }
  void constraint_jacobian(double t, const VectorXd& q, std::vector<std::vector<double>>& G, VectorXd* gt) override {
    double xb, yb, dxb, dyb;
    axle(t, xb, yb, dxb, dyb);
    const double dx = q[0] - q[2], dy = q[1] - q[3];
    G[0] = {xb, yb};
    G[1] = {2 * dx, 2 * dy, -2 * dx, -2 * dy};
    if (gt) {
      gt->resize(2);
      (*gt)[0] = dxb * q[0] + dyb * q[1];
      (*gt)[1] = 0;
    }
  }
  void add_constraint_hessian(double, const VectorXd&, const VectorXd& w, double scale, double* values) override {
    const double c = 2 * scale * w[1];  // g_0 is linear in q
    for (int i = 0; i < 4; ++i) {
      values[i * 4 + i] += c;
      values[i * 4 + (i + 2) % 4] -= c;
    }
  }
  // d(G v + dg/dt)/dq.
  void constraint_velocity_jacobian(double t, const VectorXd&, const VectorXd& v,
                                    std::vector<std::vector<double>>& rows) override {
    double xb, yb, dxb, dyb;
    axle(t, xb, yb, dxb, dyb);
    const double du = v[0] - v[2], dv = v[1] - v[3];
    rows[0] = {dxb, dyb};
    rows[1] = {2 * du, 2 * dv, -2 * du, -2 * dv};
  }
  // d/dt of (x_b u_l + y_b v_l + x_b' x_l + y_b' y_l) at fixed q, v (x_b^2 + y_b^2 = L^2 gives x_b'').
  VectorXd constraint_velocity_t(double t, const VectorXd& q, const VectorXd& v) const override {
    double xb, yb, dxb, dyb;
    axle(t, xb, yb, dxb, dyb);
    const double ddyb = -kR * kW * kW * std::sin(kW * t), ddxb = -(dxb * dxb + dyb * dyb + yb * ddyb) / xb;
    VectorXd r = VectorXd::Zero(2);
    r[0] = dxb * v[0] + dyb * v[1] + ddxb * q[0] + ddyb * q[1];
    return r;
  }
  double end_time() const override { return 3.0; }
  // The IVP test set's reference at t = 3 (y1..y8; y9, y10 with the opposite sign).
  void reference(VectorXd& q, VectorXd& v, VectorXd& lambda) const override {
    q.resize(4);
    q << 0.4934557842755629e-1, 0.4969894602303324, 0.1041742524885400e1, 0.3739110272652214;
    v.resize(4);
    v << -0.7705836840321485e-1, 0.7446866596327776e-2, 0.1755681574942899e-1, 0.7703410437794031;
    lambda.resize(2);
    lambda << 0.4736886750784630e-2, 0.1104680411345730e-2;
  }

 private:
  static void spring(double px, double py, double& fx, double& fy) {
    const double l = std::hypot(px, py);
    fx = (kL0 - l) * px / l;
    fy = (kL0 - l) * py / l;
  }
  static void spring_jacobian(double px, double py, int at, double* K) {
    const double l = std::hypot(px, py), nx = px / l, ny = py / l, c = kL0 / l;
    const double k[2][2] = {{1 - c * (1 - nx * nx), c * nx * ny}, {c * nx * ny, 1 - c * (1 - ny * ny)}};
    for (int r = 0; r < 2; ++r)
      for (int s = 0; s < 2; ++s) K[(at + s) * 4 + at + r] += k[r][s];
  }
  int group_;
  VectorXd mass_;
  SparsePattern pattern_;
  std::vector<std::vector<Index>> rows_{{0, 1}, {0, 1, 2, 3}};
};

// Frames every 10 ms from 0 to `end`, the last one at `end`: where runs are compared along the way.
inline std::vector<double> dae_frames(double end) {
  std::vector<double> t;
  for (int k = 0; k * 0.01 <= end + 1e-12; ++k) t.push_back(k * 0.01);
  t.back() = end;
  return t;
}

// A run of a test DAE over dae_frames(), measured against its reference on those frames.
struct DaeRun {
  double end_digits = 0, trajectory_digits = 0, lambda_digits = 0;
  VectorXd q, v, lambda;  // at the end
  RunStats stats;
};
inline DaeRun run_dae(TestDae& d, Integrator& integ, const std::vector<VectorXd>& qr, const std::vector<VectorXd>& vr) {
  DaeRun r;
  std::vector<VectorXd> qs, vs;
  r.stats = integ.run(dae_frames(d.end_time()), [&](int, double, const VectorXd& q, const VectorXd& v,
                                                    const VectorXd& l, const RunStats::FrameSample&) {
    qs.push_back(q);
    vs.push_back(v);
    r.lambda = l;
  });
  r.q = qs.back();
  r.v = vs.back();
  r.end_digits = d.correct_digits(r.q, r.v);
  r.trajectory_digits = TestDae::trajectory_digits(qs, vs, qr, vr);
  r.lambda_digits = d.multiplier_digits(r.lambda);
  return r;
}

}  // namespace isochor::test
