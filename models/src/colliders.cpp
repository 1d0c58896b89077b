#include "isochor/models/colliders.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <limits>

#include "isochor/models/skeleton.hpp"

namespace isochor {

namespace {

// Signed distance to a box with rounded edges in N dimensions, from q_i = |y_i| - a_i (a: the
// half extents of the inner box; the rounding radius rho is subtracted by the caller): outside
// the inner box |max(q, 0)|, inside max_i q_i. Gradient and Hessian with respect to q.
template <int N>
double rounded_box(const Eigen::Matrix<double, N, 1>& q, Eigen::Matrix<double, N, 1>& g,
                   Eigen::Matrix<double, N, N>& H) {
  g.setZero();
  H.setZero();
  const Eigen::Matrix<double, N, 1> o = q.cwiseMax(0.0);
  const double d = o.norm();
  if (d > 0) {
    g = o / d;
    for (int i = 0; i < N; ++i)
      if (q[i] > 0) H(i, i) = 1.0;
    H = (H - g * g.transpose()) / d;
    return d;
  }
  int i;
  const double m = q.maxCoeff(&i);
  g[i] = 1.0;
  return m;
}

double sign_of(double v) { return v < 0 ? -1.0 : 1.0; }

}  // namespace

const char* ColliderShape::name() const {
  switch (kind) {
    case Kind::plane:
      return "plane";
    case Kind::sphere:
      return "sphere";
    case Kind::capsule:
      return "capsule";
    case Kind::box:
      return "box";
    case Kind::cylinder:
      return wall > 0 ? "hollow cylinder" : "cylinder";
    case Kind::mesh:
      return "mesh";
  }
  return "?";
}

double ColliderShape::bound() const {
  switch (kind) {
    case Kind::plane:
      return std::numeric_limits<double>::infinity();
    case Kind::sphere:
      return radius;
    case Kind::capsule:
      return half_length + radius;
    case Kind::box:
      return half_extents.norm();
    case Kind::cylinder:
      return std::hypot(radius + wall, half_length);
    case Kind::mesh:
      return mesh->bound();
  }
  return 0;
}

double ColliderShape::distance(const Vec3& l, Vec3* grad, Mat3* hess) const {
  Vec3 g = Vec3::UnitZ();
  Mat3 H = Mat3::Zero();
  double s = 0;
  switch (kind) {
    case Kind::plane:
      s = l.z();
      break;
    case Kind::sphere:
    case Kind::capsule: {
      // Distance to the axis segment [-L, L] e_z (a point for the sphere) minus the radius.
      const double L = kind == Kind::capsule ? half_length : 0.0;
      const double zc = std::clamp(l.z(), -L, L);
      const Vec3 e = l - Vec3(0, 0, zc);
      const double d = e.norm();
      s = d - radius;
      if (d > 0) {
        g = e / d;
        Mat3 P = Mat3::Identity();
        if (std::abs(l.z()) < L) P(2, 2) = 0.0;  // beside the segment: distance to the line
        H = (P - g * g.transpose()) / d;
      }
      break;
    }
    case Kind::box: {
      Vec3 q, gq;
      Mat3 Hq;
      for (int i = 0; i < 3; ++i) q[i] = std::abs(l[i]) - (half_extents[i] - rounding);
      s = rounded_box<3>(q, gq, Hq) - rounding;
      const Vec3 sg(sign_of(l.x()), sign_of(l.y()), sign_of(l.z()));
      g = sg.cwiseProduct(gq);
      H = sg.asDiagonal() * Hq * sg.asDiagonal();
      break;
    }
    case Kind::cylinder: {
      // A rounded rectangle in (r, z), r the distance from the axis, revolved: solid, r in
      // [-R, R]; hollow, r in [R, R + wall].
      const double r = std::hypot(l.x(), l.y());
      const double rc = wall > 0 ? radius + 0.5 * wall : 0.0, hw = wall > 0 ? 0.5 * wall : radius;
      const double sr = wall > 0 ? sign_of(r - rc) : 1.0, sz = sign_of(l.z());
      Eigen::Vector2d q(sr * (r - rc) - (hw - rounding), sz * l.z() - (half_length - rounding)), gq;
      Eigen::Matrix2d Hq;
      s = rounded_box<2>(q, gq, Hq) - rounding;
      const Vec3 er = r > 0 ? Vec3(l.x() / r, l.y() / r, 0.0) : Vec3::UnitX();
      const Vec3 ez = Vec3::UnitZ();
      const Vec3 dr = sr * er, dz = sz * ez;  // dq/dl
      g = gq[0] * dr + gq[1] * dz;
      H = Hq(0, 0) * dr * dr.transpose() + Hq(0, 1) * (dr * dz.transpose() + dz * dr.transpose()) +
          Hq(1, 1) * dz * dz.transpose();
      if (r > 0) {  // the curvature of r: d2r/dl2 = (I_xy - er er^T) / r
        Mat3 Pxy = Mat3::Identity();
        Pxy(2, 2) = 0.0;
        H += gq[0] * sr * (Pxy - er * er.transpose()) / r;
      }
      break;
    }
    case Kind::mesh:
      s = mesh->distance(l, &g, hess ? &H : nullptr);
      break;
  }
  if (grad) *grad = g;
  if (hess) *hess = H;
  return s;
}

Mat3 frame_with_axis(const Vec3& axis, double angle) {
  const Vec3 z = axis.normalized();
  const Vec3 x = (std::abs(z.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(z).normalized();
  Mat3 F;
  F << x, z.cross(x), z;
  return Eigen::AngleAxisd(angle, z).toRotationMatrix() * F;
}

Collider Collider::plane(const Vec3& point, const Vec3& normal, const ContactLaw& law) {
  Collider c;
  c.shape.kind = ColliderShape::Kind::plane;
  c.center = point;
  c.rotation = frame_with_axis(normal);
  c.law = law;
  return c;
}

ColliderPose Collider::pose(double t, const Skeleton* skeleton) const {
  // The motion (Rm, tm, omega, tm'), then the rest pose under it: A = Rm R0, b = Rm c0 + tm.
  Mat3 Rm = Mat3::Identity();
  ColliderPose p;
  if (bone >= 0) {
    skeleton->realize(t);
    // Bone frames: x = R (X - origin) + p, velocity v + w x (x - p) (skeleton.hpp).
    const Vec3 origin = skeleton->bones()[bone].origin;
    Rm = skeleton->rotation(bone);
    p.omega = skeleton->angular_velocity(bone);
    p.origin = skeleton->position(bone) - Rm * origin;
    p.origin_velocity = skeleton->velocity(bone) - p.omega.cross(Rm * origin);
  } else if (motion.rotation) {
    // Turning about the axis through motion.center: x = c + R (X - c).
    const double theta = motion.displacement(t).x();
    Rm = Eigen::AngleAxisd(theta, motion.axis).toRotationMatrix();
    p.omega = motion.velocity(t).x() * motion.axis;
    p.origin = motion.center - Rm * motion.center;
    p.origin_velocity = -p.omega.cross(Rm * motion.center);
  } else {
    p.origin = motion.displacement(t);
    p.origin_velocity = motion.velocity(t);
  }
  p.A = Rm * rotation;
  p.b = Rm * center + p.origin;
  if (resize.kind != Driver::Kind::fixed) p.radius_scale = resize.displacement(t).x();
  return p;
}

double Collider::distance(const ColliderPose& p, const Vec3& x, Vec3* grad, Mat3* hess) const {
  const Vec3 l = p.A.transpose() * (x - p.b);
  Vec3 gl;
  Mat3 Hl;
  double s;
  if (p.radius_scale != 1.0) {
    ColliderShape scaled = shape;
    scaled.radius *= p.radius_scale;
    s = scaled.distance(l, grad ? &gl : nullptr, hess ? &Hl : nullptr);
  } else {
    s = shape.distance(l, grad ? &gl : nullptr, hess ? &Hl : nullptr);
  }
  if (grad) *grad = p.A * gl;
  if (hess) *hess = p.A * Hl * p.A.transpose();
  return s;
}

}  // namespace isochor
