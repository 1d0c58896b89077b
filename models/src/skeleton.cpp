#include "isochor/models/skeleton.hpp"

#include <Eigen/Geometry>
#include <Simbody.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <optional>

#include "isochor/base/error.hpp"

namespace isochor {

Eigen::Vector4d BoneSpec::quaternion(double t, Eigen::Vector4d* rate) const {
  if (!key_quaternions.empty()) {
    // q = p / |p| with p the cubic through the keys: q' = (p' - q (q . p')) / |p|.
    Eigen::Vector4d p, dp;
    cubic_keys(key_times, key_quaternions, t, p, dp);
    const double n = p.norm();
    const Eigen::Vector4d q = p / n;
    if (rate) *rate = (dp - q * q.dot(dp)) / n;
    return q;
  }
  // Angles: the product of axis quaternions (continuous in t), and q' = 1/2 (0, w) q.
  Eigen::Vector3d w;
  rotation(t, rate ? &w : nullptr);
  const Eigen::Vector3d a = motion.displacement(t);
  Eigen::Quaterniond Q = Eigen::Quaterniond::Identity();
  for (int k = 0; k < angles; ++k) Q = Q * Eigen::Quaterniond(Eigen::AngleAxisd(a[k], axes.col(k)));
  if (rate) {
    const Eigen::Quaterniond D = Eigen::Quaterniond(0, w.x(), w.y(), w.z()) * Q;
    *rate = 0.5 * Eigen::Vector4d(D.w(), D.x(), D.y(), D.z());
  }
  return Eigen::Vector4d(Q.w(), Q.x(), Q.y(), Q.z());
}

void BoneSpec::breakpoints(std::vector<double>& out) const {
  motion.breakpoints(out);
  translation.breakpoints(out);
  if (!key_times.empty()) out.insert(out.end(), {key_times.front(), key_times.back()});
}

Eigen::Matrix3d BoneSpec::rotation(double t, Eigen::Vector3d* omega) const {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  if (omega) omega->setZero();
  if (!key_quaternions.empty()) {
    // w = 2 vec(q' conj(q)).
    Eigen::Vector4d dq;
    const Eigen::Vector4d q = quaternion(t, omega ? &dq : nullptr);
    if (omega) {
      const Eigen::Quaterniond W =
          Eigen::Quaterniond(dq[0], dq[1], dq[2], dq[3]) * Eigen::Quaterniond(q[0], q[1], q[2], q[3]).conjugate();
      *omega = 2 * W.vec();
    }
    return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).toRotationMatrix();
  }
  if (angles == 0) return R;
  const Eigen::Vector3d a = motion.displacement(t);
  const Eigen::Vector3d da = omega ? motion.velocity(t) : Eigen::Vector3d::Zero();
  // Body-fixed sequence: R = R_1 R_2 R_3 with each axis given in the rest frame;
  // w = a1' e1 + R_1 e2 a2' + R_1 R_2 e3 a3' (in the parent frame).
  for (int k = 0; k < angles; ++k) {
    const Eigen::Vector3d e = axes.col(k);
    if (omega) *omega += da[k] * (R * e);
    R = R * Eigen::AngleAxisd(a[k], e).toRotationMatrix();
  }
  return R;
}

double BoneSpec::segment_distance(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d d = to - from;
  const double n2 = d.squaredNorm();
  const double s = n2 > 0 ? std::clamp((p - from).dot(d) / n2, 0.0, 1.0) : 0.0;
  return (p - (from + s * d)).norm();
}

namespace {

SimTK::Vec3 vec(const Eigen::Vector3d& v) { return SimTK::Vec3(v.x(), v.y(), v.z()); }
Eigen::Vector3d vec(const SimTK::Vec3& v) { return Eigen::Vector3d(v[0], v[1], v[2]); }

// The frame F of a joint: pin turns about F's z; universal about F's x then the new y.
Eigen::Matrix3d joint_frame(const BoneSpec& b) {
  Eigen::Matrix3d F = Eigen::Matrix3d::Identity();
  if (b.joint == BoneSpec::Joint::pin) {
    const Eigen::Vector3d z = b.axes.col(0);
    const Eigen::Vector3d x =
        (std::abs(z.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY()).cross(z).normalized();
    F << x, z.cross(x), z;
  } else if (b.joint == BoneSpec::Joint::universal) {
    F << b.axes.col(0), b.axes.col(1), b.axes.col(0).cross(b.axes.col(1));
  }
  return F;
}

// Prescribed position-level motion of one joint: q(t) are its angles (pin, universal) or the
// quaternion of its rotation (ball).
class JointMotion : public SimTK::Motion::Custom::Implementation {
 public:
  explicit JointMotion(const BoneSpec* b) : b_(b) {}
  Implementation* clone() const override { return new JointMotion(*this); }
  SimTK::Motion::Level getLevel(const SimTK::State&) const override { return SimTK::Motion::Position; }
  void calcPrescribedPosition(const SimTK::State& s, int nq, SimTK::Real* q) const override {
    eval(s.getTime(), nq, q, nullptr);
  }
  void calcPrescribedPositionDot(const SimTK::State& s, int nq, SimTK::Real* qd) const override {
    eval(s.getTime(), nq, nullptr, qd);
  }
  void calcPrescribedPositionDotDot(const SimTK::State& s, int nq, SimTK::Real* qdd) const override {
    // Only the acceleration stage asks for it, which isochor never realizes: a central difference.
    const double h = 1e-6;
    SimTK::Real a[7], b[7];  // free: quaternion and translation
    eval(s.getTime() + h, nq, nullptr, a);
    eval(s.getTime() - h, nq, nullptr, b);
    for (int k = 0; k < nq; ++k) qdd[k] = (a[k] - b[k]) / (2 * h);
  }

 private:
  // Pin and universal: the angles. Ball: the quaternion (w, x, y, z). Free: the quaternion, then
  // the origin's displacement.
  void eval(double t, int nq, SimTK::Real* q, SimTK::Real* qd) const {
    if (b_->joint != BoneSpec::Joint::ball && b_->joint != BoneSpec::Joint::free) {
      const Eigen::Vector3d a = b_->motion.displacement(t), da = b_->motion.velocity(t);
      for (int k = 0; k < nq && k < 3; ++k) {
        if (q) q[k] = a[k];
        if (qd) qd[k] = da[k];
      }
      return;
    }
    Eigen::Vector4d dv;
    const Eigen::Vector4d v = b_->quaternion(t, qd ? &dv : nullptr);
    for (int k = 0; k < nq && k < 4; ++k) {
      if (q) q[k] = v[k];
      if (qd) qd[k] = dv[k];
    }
    if (nq < 7) return;
    const Eigen::Vector3d u = b_->translation.displacement(t), du = b_->translation.velocity(t);
    for (int k = 0; k < 3; ++k) {
      if (q) q[4 + k] = u[k];
      if (qd) qd[4 + k] = du[k];
    }
  }
  const BoneSpec* b_;
};

}  // namespace

struct Skeleton::Impl {
  SimTK::MultibodySystem system;
  SimTK::SimbodyMatterSubsystem matter{system};
  std::vector<SimTK::MobilizedBodyIndex> index;
  SimTK::State state;  // realize()'s memo: the state at Skeleton::t_
};

Skeleton::Skeleton(std::vector<BoneSpec> bones)
    : bones_(std::move(bones)), pose_(bones_.size()), impl_(std::make_unique<Impl>()) {
  using SimTK::MobilizedBody, SimTK::MobilizedBodyIndex, SimTK::Transform, SimTK::Rotation, SimTK::Mat33;
  const SimTK::Body::Rigid body(SimTK::MassProperties(1.0, SimTK::Vec3(0), SimTK::UnitInertia(1.0)));
  for (std::size_t i = 0; i < bones_.size(); ++i) {
    const BoneSpec& b = bones_[i];
    MobilizedBody& parent =
        b.parent < 0 ? impl_->matter.updGround() : impl_->matter.updMobilizedBody(impl_->index[b.parent]);
    const Eigen::Vector3d parent_origin = b.parent < 0 ? Eigen::Vector3d::Zero() : bones_[b.parent].origin;
    const Eigen::Matrix3d F = joint_frame(b);
    Mat33 f;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) f(r, c) = F(r, c);
    const Transform X_PF(Rotation(f), vec(Eigen::Vector3d(b.origin - parent_origin))),
        X_BM(Rotation(f), SimTK::Vec3(0));
    MobilizedBodyIndex idx;
    switch (b.joint) {
      case BoneSpec::Joint::weld:
        idx = MobilizedBody::Weld(parent, X_PF, body, X_BM).getMobilizedBodyIndex();
        break;
      case BoneSpec::Joint::pin:
        idx = MobilizedBody::Pin(parent, X_PF, body, X_BM).getMobilizedBodyIndex();
        break;
      case BoneSpec::Joint::universal:
        idx = MobilizedBody::Universal(parent, X_PF, body, X_BM).getMobilizedBodyIndex();
        break;
      case BoneSpec::Joint::ball:
        idx = MobilizedBody::Ball(parent, X_PF, body, X_BM).getMobilizedBodyIndex();
        break;
      case BoneSpec::Joint::free:
        idx = MobilizedBody::Free(parent, X_PF, body, X_BM).getMobilizedBodyIndex();
        break;
    }
    impl_->index.push_back(idx);
    if (b.joint != BoneSpec::Joint::weld)
      SimTK::Motion::Custom(impl_->matter.updMobilizedBody(idx), new JointMotion(&bones_[i]));
  }
  impl_->state = impl_->system.realizeTopology();
  impl_->system.realizeModel(impl_->state);
}

Skeleton::~Skeleton() = default;

void Skeleton::realize(double t) const {
  if (t == t_) return;
  using SimTK::State, SimTK::Stage, SimTK::MobilizedBody, SimTK::Transform, SimTK::SpatialVec, SimTK::Mat33;
  const auto start = std::chrono::steady_clock::now();
  State& s = impl_->state;
  s.setTime(t);
  impl_->system.realize(s, Stage::Time);
  impl_->system.prescribeQ(s);
  impl_->system.realize(s, Stage::Position);
  impl_->system.prescribeU(s);
  impl_->system.realize(s, Stage::Velocity);
  for (std::size_t i = 0; i < bones_.size(); ++i) {
    const MobilizedBody& mb = impl_->matter.getMobilizedBody(impl_->index[i]);
    const Transform& X = mb.getBodyTransform(s);
    const SpatialVec& V = mb.getBodyVelocity(s);
    const Mat33& R = X.R().asMat33();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) pose_[i].R(r, c) = R(r, c);
    pose_[i].p = vec(X.p());
    pose_[i].w = vec(V[0]);
    pose_[i].v = vec(V[1]);
  }
  t_ = t;
  ++realizations_;
  seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void Skeleton::apply(const Points& rest, double t, Points& x, Eigen::VectorXd* xdot) const {
  realize(t);
  for (std::size_t i = 0; i < bones_.size(); ++i) {
    const Pose& P = pose_[i];
    for (int n : bones_[i].nodes) {
      const Eigen::Vector3d r = P.R * (rest.col(n) - bones_[i].origin);
      x.col(n) = P.p + r;
      if (xdot) xdot->segment<3>(3 * n) = P.v + P.w.cross(r);
    }
  }
}

std::vector<int> Skeleton::bound_nodes() const {
  std::vector<int> all;
  for (const BoneSpec& b : bones_) all.insert(all.end(), b.nodes.begin(), b.nodes.end());
  std::sort(all.begin(), all.end());
  return all;
}

}  // namespace isochor
