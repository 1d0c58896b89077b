// A rigged skeleton: bones joined by weld, pin, universal and ball joints whose angles are given
// functions of time (keyframes, sinusoid, or a BVH motion file), evaluated by Simbody as
// prescribed motion. Mesh nodes bound to a bone follow it rigidly: x = X_GB(t) s, with s the
// node's rest position in the bone's frame. Simbody is only built for scenes with a skeleton.
//
// Frames: in the rest pose every bone frame is parallel to the world axes with its origin at the
// bone's joint (`origin`, world coordinates). A joint's rotation R(t) turns the bone about its
// origin relative to its parent: pin, angle a about `axis`; universal, a1 about `axis` then a2
// about the turned `axis2`; ball, body-fixed rotations about the axes in `order` (e.g. "ZXY",
// BVH's convention: R = R_Z(a1) R_X(a2) R_Y(a3)). A keyed joint (a glTF character's) turns by unit
// quaternions at key times instead of angles; a free joint also moves its origin (a character's root).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "isochor/models/drivers.hpp"
#include "isochor/core/mesh.hpp"

namespace isochor {

struct BoneSpec {
  enum class Joint { weld, pin, universal, ball, free };
  std::string name;
  int parent = -1;  // index of the parent bone, -1: the ground
  Joint joint = Joint::weld;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // the joint, rest pose, world
  // The capsule that binds nodes by distance: its axis segment from-to (rest pose) and radius.
  Eigen::Vector3d from = Eigen::Vector3d::Zero(), to = Eigen::Vector3d::Zero();
  double radius = 0;
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  // columns: the joint's rotation axes in order
  int angles = 0;                                      // 0 weld, 1 pin, 2 universal, 3 ball
  Driver motion;           // angles (rad) of the joint in x, y, z of its values; Kind::fixed: zero
  std::vector<int> nodes;  // bound mesh nodes
  // Keyed rotation (ball and free joints; replaces the angles): unit quaternions (w, x, y, z)
  // relative to the parent at key times, neighbours of one sign (q and -q are one rotation);
  // between keys the C^1 cubic through their components (cubic_keys), normalised.
  std::vector<double> key_times;
  std::vector<Eigen::Vector4d> key_quaternions;
  // Free joints: the origin's displacement from its rest place, in the parent's rest frame.
  Driver translation;

  // The joint's quaternion (w, x, y, z) at t and its rate q' = 1/2 (0, w) q (w in the parent frame).
  Eigen::Vector4d quaternion(double t, Eigen::Vector4d* rate = nullptr) const;
  // Times where the joint's motion starts or stops or its velocity jumps (Driver::breakpoints).
  void breakpoints(std::vector<double>& out) const;

  // The joint rotation relative to the parent, and its angular velocity (parent frame), at t.
  Eigen::Matrix3d rotation(double t, Eigen::Vector3d* omega = nullptr) const;
  // Distance from a rest-pose point to the capsule's axis segment.
  double segment_distance(const Eigen::Vector3d& p) const;
};

class Skeleton {
 public:
  explicit Skeleton(std::vector<BoneSpec> bones);
  ~Skeleton();
  Skeleton(const Skeleton&) = delete;
  Skeleton& operator=(const Skeleton&) = delete;

  const std::vector<BoneSpec>& bones() const { return bones_; }
  // Realizes the Simbody state at t (position and velocity stages). The bones' motion is a
  // function of t alone (prescribed motion), so the Simbody state and the poses are a memo of the
  // last t: const, and the same answer whoever asked before (every system that drives nodes by
  // this skeleton shares it; only the cost differs).
  void realize(double t) const;
  // Bone b's frame in the world at the realized t: x = R s + p; velocity v + w x (R s).
  const Eigen::Matrix3d& rotation(int b) const { return pose_[b].R; }
  const Eigen::Vector3d& position(int b) const { return pose_[b].p; }
  const Eigen::Vector3d& angular_velocity(int b) const { return pose_[b].w; }
  const Eigen::Vector3d& velocity(int b) const { return pose_[b].v; }
  // Moves the bound nodes (and sets their velocities) to time t.
  void apply(const Points& rest, double t, Points& x, Eigen::VectorXd* xdot) const;
  // Every bound node, sorted.
  std::vector<int> bound_nodes() const;
  // Wall seconds spent realizing Simbody states, and how many realizations.
  double simbody_seconds() const { return seconds_; }
  long realizations() const { return realizations_; }

 private:
  struct Pose {
    Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
    Eigen::Vector3d p = Eigen::Vector3d::Zero(), w = Eigen::Vector3d::Zero(), v = Eigen::Vector3d::Zero();
  };
  struct Impl;
  std::vector<BoneSpec> bones_;
  // The memo of realize(): Simbody's state (in impl_), the poses at t_, and its cost.
  mutable std::vector<Pose> pose_;
  std::unique_ptr<Impl> impl_;
  mutable double t_ = std::numeric_limits<double>::quiet_NaN(), seconds_ = 0;
  mutable long realizations_ = 0;
};

}  // namespace isochor
