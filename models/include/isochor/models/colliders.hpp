// Rigid colliders: shapes the tissue cannot enter (the ground, planes, spheres, capsules, boxes,
// solid or hollow cylinders), static, moved by a driver's motion, or carried by a bone.
//
// Each shape is a signed distance s(l) in its own frame (l: local coordinates, positive outside
// the shape), with its gradient and Hessian. A collider places the shape in the world by a rest
// pose (centre c0, rotation R0 whose third column is the shape's axis) and a rigid motion
// (Rm(t), tm(t)): a local point l is at x = Rm (R0 l + c0) + tm. Its material at x moves at
// w(x) = omega x (x - tm) + tm'. Contact acts on nodes through the node's s (elements.hpp:
// contact_energy, contact_damping_force).
//
// A closed triangle mesh's s is the cubic B-spline of its exact signed distance sampled on a grid
// (mesh_sdf.hpp): C^2 everywhere, edges and corners rounded over about two cells.
//
// Smoothness: s is C^1 near every shape's surface where the surface is C^1 (the box's and the
// cylinder's edges are rounded by `rounding` for that; a penetration deeper than the rounding
// radius meets the inner box's medial axis, where the gradient jumps); s is C^2 (and the force
// k (delta - s)^2 grad s is C^1) except across the lines where the surface's curvature jumps (a
// capsule's cap seams, a rounded edge's border with a flat face), where the force stays
// continuous with a bounded derivative.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "isochor/models/drivers.hpp"
#include "isochor/models/elements.hpp"
#include "isochor/models/mesh_sdf.hpp"

namespace isochor {

class Skeleton;

struct ColliderShape {
  enum class Kind { plane, sphere, capsule, box, cylinder, mesh };
  Kind kind = Kind::plane;
  double radius = 0;                 // sphere, capsule; cylinder: the outer radius (solid) or the hole's (hollow)
  double half_length = 0;            // capsule: half its axis segment; cylinder: half its height
  Vec3 half_extents = Vec3::Zero();  // box
  double rounding = 0;               // box, cylinder: radius of the rounded edges
  double wall = 0;                   // cylinder: > 0 makes it hollow (a band, a sleeve) with this wall thickness
  std::shared_ptr<const MeshSdf> mesh = nullptr;  // mesh: the closed surface's smoothed signed distance

  // Signed distance at the local point l; gradient and Hessian (local frame) if asked.
  double distance(const Vec3& l, Vec3* grad, Mat3* hess) const;
  // A radius about the local origin outside which the distance is at least |l| - bound (every
  // point of the shape lies within it); infinity for a plane.
  double bound() const;
  const char* name() const;
};

// How a collider pushes: the ground's C^2 penalty k/3 (delta - s)^3 per node (or per rest surface
// area), Hunt-Crossley normal damping alpha, and smoothed Coulomb friction.
struct ContactLaw {
  double stiffness = 1e6;   // k: N/m^3 per node, N/m^4 per area
  double thickness = 1e-3;  // delta, m
  bool per_area = false;
  double damping = 0.0;      // alpha, s/m
  double friction = 0.0;     // Coulomb coefficient mu_c (0: frictionless)
  double slip_speed = 1e-3;  // m/s: tangential speed below which friction grows linearly (smoothing)
};

// Where a collider is at one time: local -> world x = A l + b; the material's velocity at x is
// omega x (x - origin) + origin_velocity.
struct ColliderPose {
  Mat3 A = Mat3::Identity();
  Vec3 b = Vec3::Zero();
  Vec3 omega = Vec3::Zero(), origin = Vec3::Zero(), origin_velocity = Vec3::Zero();
  double radius_scale = 1.0;  // the shape's radius is scaled by this (Collider::resize)
  Vec3 velocity_at(const Vec3& x) const { return omega.cross(x - origin) + origin_velocity; }
};

struct Collider {
  std::string name;  // for messages: "contact.ground", "collider[2]", ...
  ColliderShape shape;
  ContactLaw law;
  Vec3 center = Vec3::Zero();        // rest pose
  Mat3 rotation = Mat3::Identity();  // rest pose; column 2 is the shape's axis (a plane's normal)
  Driver motion;                     // Kind::fixed: static; a ramp, keyframes, sinusoid or rotation
  int bone = -1;                     // >= 0: carried by this bone of the scene's skeleton
  // A factor on the radius in time (keyframes in x of its values; Kind::fixed: 1): a band that
  // tightens. The sphere's, capsule's or cylinder's radius (a hollow one's hole; its wall and
  // rounding stay). Not with damping or friction (their velocity would need the radius' rate).
  Driver resize;

  // The pose at t (a bone's needs the skeleton, realized at t by this call).
  ColliderPose pose(double t, const Skeleton* skeleton) const;
  // Signed distance of the world point x at this pose; world gradient and Hessian if asked.
  double distance(const ColliderPose& p, const Vec3& x, Vec3* grad, Mat3* hess) const;

  // A plane through `point` with normal `normal` (normalised here) and the given law.
  static Collider plane(const Vec3& point, const Vec3& normal, const ContactLaw& law);
};

// The rotation whose third column is `axis` (normalised), turned by `angle` (rad) about it.
Mat3 frame_with_axis(const Vec3& axis, double angle = 0.0);

}  // namespace isochor
