#include "isochor/skeleton.hpp"

#include <Eigen/Geometry>
#include <Simbody.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <optional>

#include "isochor/bvh.hpp"
#include "isochor/error.hpp"
#include "isochor/scene.hpp"
#include "isochor/scene_file.hpp"
#include "isochor/selection.hpp"

namespace isochor {

Eigen::Matrix3d BoneSpec::rotation(double t, Eigen::Vector3d* omega) const {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  if (omega) omega->setZero();
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
    const Eigen::Vector3d x = (std::abs(z.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY()).cross(z).normalized();
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
    SimTK::Real a[4], b[4];
    eval(s.getTime() + h, nq, nullptr, a);
    eval(s.getTime() - h, nq, nullptr, b);
    for (int k = 0; k < nq; ++k) qdd[k] = (a[k] - b[k]) / (2 * h);
  }

 private:
  void eval(double t, int nq, SimTK::Real* q, SimTK::Real* qd) const {
    if (b_->joint != BoneSpec::Joint::ball) {
      const Eigen::Vector3d a = b_->motion.displacement(t), da = b_->motion.velocity(t);
      for (int k = 0; k < nq; ++k) {
        if (q) q[k] = a[k];
        if (qd) qd[k] = da[k];
      }
      return;
    }
    // Ball: the quaternion (w, x, y, z) of R = R_1 R_2 R_3, built as a product of axis
    // quaternions (continuous in t), and q' = 1/2 (0, w) * q with w in the parent frame.
    Eigen::Vector3d w;
    b_->rotation(t, &w);
    const Eigen::Vector3d a = b_->motion.displacement(t);
    Eigen::Quaterniond Q = Eigen::Quaterniond::Identity();
    for (int k = 0; k < 3; ++k) Q = Q * Eigen::Quaterniond(Eigen::AngleAxisd(a[k], b_->axes.col(k)));
    const Eigen::Quaterniond W(0, w.x(), w.y(), w.z());
    const Eigen::Quaterniond D = W * Q;
    const double v[4] = {Q.w(), Q.x(), Q.y(), Q.z()}, dv[4] = {0.5 * D.w(), 0.5 * D.x(), 0.5 * D.y(), 0.5 * D.z()};
    for (int k = 0; k < nq && k < 4; ++k) {
      if (q) q[k] = v[k];
      if (qd) qd[k] = dv[k];
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

Skeleton::Skeleton(std::vector<BoneSpec> bones) : bones_(std::move(bones)), pose_(bones_.size()), impl_(std::make_unique<Impl>()) {
  using SimTK::MobilizedBody, SimTK::MobilizedBodyIndex, SimTK::Transform, SimTK::Rotation, SimTK::Mat33;
  const SimTK::Body::Rigid body(SimTK::MassProperties(1.0, SimTK::Vec3(0), SimTK::UnitInertia(1.0)));
  for (std::size_t i = 0; i < bones_.size(); ++i) {
    const BoneSpec& b = bones_[i];
    MobilizedBody& parent = b.parent < 0 ? impl_->matter.updGround() : impl_->matter.updMobilizedBody(impl_->index[b.parent]);
    const Eigen::Vector3d parent_origin = b.parent < 0 ? Eigen::Vector3d::Zero() : bones_[b.parent].origin;
    const Eigen::Matrix3d F = joint_frame(b);
    Mat33 f;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) f(r, c) = F(r, c);
    const Transform X_PF(Rotation(f), vec(Eigen::Vector3d(b.origin - parent_origin))), X_BM(Rotation(f), SimTK::Vec3(0));
    MobilizedBodyIndex idx;
    switch (b.joint) {
      case BoneSpec::Joint::weld: idx = MobilizedBody::Weld(parent, X_PF, body, X_BM).getMobilizedBodyIndex(); break;
      case BoneSpec::Joint::pin: idx = MobilizedBody::Pin(parent, X_PF, body, X_BM).getMobilizedBodyIndex(); break;
      case BoneSpec::Joint::universal: idx = MobilizedBody::Universal(parent, X_PF, body, X_BM).getMobilizedBodyIndex(); break;
      case BoneSpec::Joint::ball: idx = MobilizedBody::Ball(parent, X_PF, body, X_BM).getMobilizedBodyIndex(); break;
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

namespace {

// Angles of a joint from a BVH joint's rotation channels: the axis order and keyframes (cubic,
// one per BVH frame), unwrapped so that no step between frames exceeds 180 degrees.
void bvh_motion(const Section& b, const Bvh& bvh, const std::string& joint, BoneSpec& bone) {
  const int j = bvh.find(joint);
  if (j < 0) b.fail("bvh_joint", "\"" + joint + "\" is not a joint of the BVH file");
  const BvhJoint& J = bvh.joints[j];
  std::vector<int> columns;
  std::string order;
  for (std::size_t c = 0; c < J.channels.size(); ++c) {
    const int ch = J.channels[c];
    if (ch < BvhJoint::Xrotation) continue;
    columns.push_back(J.first_channel + static_cast<int>(c));
    bone.axes.col(static_cast<Eigen::Index>(order.size())) = Eigen::Vector3d::Unit(ch - BvhJoint::Xrotation);
    order += static_cast<char>('X' + (ch - BvhJoint::Xrotation));
  }
  if (columns.size() != 3)
    b.fail("bvh_joint", "\"" + joint + "\" has " + std::to_string(columns.size()) +
                            " rotation channels, expected 3 (a ball joint)");
  bone.motion.kind = Driver::Kind::keyframes_cubic;
  Eigen::Vector3d previous = Eigen::Vector3d::Zero();
  for (Eigen::Index f = 0; f < bvh.motion.rows(); ++f) {
    Eigen::Vector3d a;
    for (int k = 0; k < 3; ++k) {
      a[k] = bvh.motion(f, columns[k]);
      if (f > 0) a[k] -= 360.0 * std::round((a[k] - previous[k]) / 360.0);
    }
    previous = a;
    bone.motion.times.push_back(static_cast<double>(f) * bvh.frame_time);
    bone.motion.values.push_back(a * M_PI / 180.0);
  }
  if (bone.motion.times.size() == 1) {  // one frame: a constant pose
    bone.motion.times.push_back(bvh.frame_time);
    bone.motion.values.push_back(bone.motion.values.front());
  }
}

Eigen::Vector3d unit(const Section& b, const std::string& key, const Eigen::Vector3d& fallback) {
  const Eigen::Vector3d v = b.vec3(key, fallback);
  if (v.norm() == 0) b.fail(key, "expected a non-zero vector");
  return v.normalized();
}

}  // namespace

std::shared_ptr<Skeleton> parse_skeleton(const Section& s, const SceneFile& file, const Mesh& mesh,
                                         const std::vector<int>& driven_by) {
  const std::vector<Section> bone_sections = s.tables("bone");
  if (!s.exists()) return nullptr;
  if (bone_sections.empty()) s.fail("bone", "missing, a [skeleton] needs at least one [[skeleton.bone]]");
  std::optional<Bvh> bvh;
  if (s.has("bvh")) bvh = read_bvh(file.resolve_path(s.string("bvh", "")));
  std::vector<BoneSpec> bones;
  std::map<std::string, int> index;
  for (const Section& b : bone_sections) {
    BoneSpec bone;
    bone.name = b.string("name", "");
    if (bone.name.empty() || bone.name == "ground") b.fail("name", "missing, expected a bone name (not \"ground\")");
    if (index.count(bone.name)) b.fail("name", "bone \"" + bone.name + "\" is defined twice");
    const std::string parent = b.string("parent", "ground");
    if (parent != "ground") {
      auto it = index.find(parent);
      if (it == index.end()) b.fail("parent", "\"" + parent + "\" is not a bone defined above (expected \"ground\" or an earlier bone)");
      bone.parent = it->second;
    }
    const std::string joint = b.string("joint", "weld", {"weld", "pin", "universal", "ball"});
    bone.origin = b.vec3("origin", Eigen::Vector3d::Zero());
    const Eigen::Vector3d direction = unit(b, "direction", Eigen::Vector3d::UnitX());
    double length = b.number("length", 0.0, Range::non_negative());
    const double start = b.number("start", 0.0, Range::non_negative());
    if (start > length && b.has("start")) b.fail("start", "expected start <= length");
    bone.radius = b.number("radius", 0.0, Range::non_negative());
    if (joint == "weld") {
      bone.joint = BoneSpec::Joint::weld;
    } else if (joint == "pin") {
      bone.joint = BoneSpec::Joint::pin;
      bone.angles = 1;
      bone.axes.col(0) = unit(b, "axis", Eigen::Vector3d::UnitZ());
    } else if (joint == "universal") {
      bone.joint = BoneSpec::Joint::universal;
      bone.angles = 2;
      bone.axes.col(0) = unit(b, "axis", Eigen::Vector3d::UnitX());
      const Eigen::Vector3d a2 = unit(b, "axis2", Eigen::Vector3d::UnitY());
      const Eigen::Vector3d y = a2 - a2.dot(bone.axes.col(0)) * bone.axes.col(0);
      if (y.norm() < 1e-6) b.fail("axis2", "expected a direction not parallel to axis");
      bone.axes.col(1) = y.normalized();
    } else {
      bone.joint = BoneSpec::Joint::ball;
      bone.angles = 3;
      const std::string order = b.string("order", "XYZ");
      if (order.size() != 3 || order.find_first_not_of("XYZ") != std::string::npos)
        b.fail("order", "expected three axis letters such as \"XYZ\" or \"ZXY\"");
      for (int k = 0; k < 3; ++k) bone.axes.col(k) = Eigen::Vector3d::Unit(order[k] - 'X');
    }
    const std::string motion = b.string("motion", "none", {"none", "keyframes", "sinusoid", "bvh"});
    if (motion != "none" && bone.joint == BoneSpec::Joint::weld)
      b.fail("motion", "a weld joint does not move (expected joint = \"pin\", \"universal\" or \"ball\")");
    const int n = bone.angles;
    const std::string per = std::to_string(n) + (n == 1 ? " angle" : " angles");
    if (motion == "keyframes") {
      bone.motion = parse_keyframes(b, "angles", n, M_PI / 180.0, per + " (degrees)");
    } else if (motion == "sinusoid") {
      const std::vector<double> amp = b.numbers("amplitude");
      if (static_cast<int>(amp.size()) != n) b.fail("amplitude", "expected " + per + " (degrees)");
      bone.motion.kind = Driver::Kind::sinusoid;
      for (int k = 0; k < n; ++k) bone.motion.vector[k] = amp[k] * M_PI / 180.0;
      bone.motion.frequency = b.number("frequency", 1.0, Range::positive());
      bone.motion.phase = b.number("phase", 0.0);
    } else if (motion == "bvh") {
      if (!bvh) s.fail("bvh", "missing, bone \"" + bone.name + "\" takes its motion from a BVH file");
      if (bone.joint != BoneSpec::Joint::ball) b.fail("joint", "motion = \"bvh\" drives ball joints (expected joint = \"ball\")");
      if (b.has("order")) b.fail("order", "comes from the BVH file's channels with motion = \"bvh\"");
      bvh_motion(b, *bvh, b.string("bvh_joint", bone.name), bone);
    }
    // Nodes: listed explicitly, or (below) those near the capsule.
    if (Section sel = b.table("select"); sel.exists()) bone.nodes = select_nodes(mesh, Selection::parse(sel));
    length = std::max(length, start);
    bone.from = b.vec3("from", bone.origin + start * direction);
    bone.to = b.vec3("to", bone.origin + length * direction);
    if ((b.has("from") || b.has("to")) && (b.has("start") || b.has("length") || b.has("direction")))
      b.fail(b.has("from") ? "from" : "to", "give the capsule either by from and to or by direction, start and length, not both");
    index[bone.name] = static_cast<int>(bones.size());
    bones.push_back(std::move(bone));
  }
  // Capsule attachment: each node within radius + attach_distance of some capsule goes to the
  // nearest one (by distance beyond the radius). Explicit selections take precedence.
  std::vector<int> bound_to(mesh.num_nodes(), -1);
  for (std::size_t i = 0; i < bones.size(); ++i)
    for (int v : bones[i].nodes) {
      if (bound_to[v] >= 0)
        bone_sections[i].fail("select", "node " + std::to_string(v) + " is already bound to bone \"" + bones[bound_to[v]].name + "\"");
      bound_to[v] = static_cast<int>(i);
    }
  std::vector<double> attach(bones.size());
  std::vector<char> listed(bones.size());  // the bone's nodes are given by `select`
  for (std::size_t i = 0; i < bones.size(); ++i) {
    attach[i] = bone_sections[i].number("attach_distance", 0.0, Range::non_negative());
    listed[i] = bone_sections[i].table("select").exists();
  }
  const Points& X = mesh.rest_positions();
  for (int v = 0; v < mesh.num_nodes(); ++v) {
    if (bound_to[v] >= 0) continue;
    double best = std::numeric_limits<double>::infinity();
    int which = -1;
    for (std::size_t i = 0; i < bones.size(); ++i) {
      if (bones[i].radius <= 0 || listed[i]) continue;
      const double d = bones[i].segment_distance(X.col(v)) - bones[i].radius;
      if (d <= attach[i] && d < best) best = d, which = static_cast<int>(i);
    }
    if (which >= 0) bound_to[v] = which, bones[which].nodes.push_back(v);
  }
  for (std::size_t i = 0; i < bones.size(); ++i) {
    std::sort(bones[i].nodes.begin(), bones[i].nodes.end());
    if ((bones[i].radius > 0 || listed[i]) && bones[i].nodes.empty())
      bone_sections[i].fail("radius", "bone \"" + bones[i].name + "\" binds no mesh node (expected its capsule, the segment from-to with this radius, to hold mesh nodes)");
    for (int v : bones[i].nodes)
      if (driven_by[v] >= 0)
        bone_sections[i].fail(listed[i] ? "select" : "radius",
                              "node " + std::to_string(v) + " of bone \"" + bones[i].name + "\" is already driven by boundary[" +
                                  std::to_string(driven_by[v]) + "] (expected each node driven once)");
  }
  return std::make_shared<Skeleton>(std::move(bones));
}

}  // namespace isochor
