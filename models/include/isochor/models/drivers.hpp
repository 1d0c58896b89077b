// Dirichlet drivers: a node set whose positions are given functions of time, x_i(t) = X_i + u(t),
// with velocities u'(t). Kinds: fixed (u = 0), ramp (u = u_end * clamp((t - t0)/(t1 - t0))),
// keyframes (piecewise linear, or cubic Hermite with Catmull-Rom tangents, zero at the first and
// last keys: C^1 everywhere, the value held outside the keys), sinusoid
// (u = amplitude * sin(2 pi f t + phase)).
#pragma once
#include <string>
#include <vector>

#include "isochor/core/mesh.hpp"

namespace isochor {

struct Driver {
  enum class Kind { fixed, ramp, keyframes_linear, keyframes_cubic, sinusoid };
  Kind kind = Kind::fixed;
  std::vector<int> nodes;
  Eigen::Vector3d vector = Eigen::Vector3d::Zero();  // ramp: end displacement; sinusoid: amplitude
  double t0 = 0, t1 = 1;                             // ramp interval
  double frequency = 1, phase = 0;                   // sinusoid
  std::vector<double> times;                         // keyframes
  std::vector<Eigen::Vector3d> values;               // keyframe displacements
  // Rotation drivers: keyframes whose values hold the angle (rad) in x; the nodes turn about the
  // axis through `center`: x = c + R(theta(t)) (X - c), v = theta'(t) axis x (x - c).
  bool rotation = false;
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ(), center = Eigen::Vector3d::Zero();
  // The unit directions the driver holds (boundary.components or boundary.normal); empty: all
  // three (the nodes follow the driver and are not unknowns). Held directions make the nodes
  // unknowns with one constraint row each (supports.hpp), u(t) acting along them.
  std::vector<Eigen::Vector3d> held;

  // Displacement and its time derivative at t.
  Eigen::Vector3d displacement(double t) const;
  Eigen::Vector3d velocity(double t) const;
  // Times where the motion is not smooth (its velocity jumps or, for cubic keyframes, starts or
  // stops): a ramp's ends, every knot of linear keyframes, the first and last of cubic ones.
  void breakpoints(std::vector<double>& out) const;
  // Writes positions and velocities (3 N vector) of the driven nodes at time t.
  void apply(const Points& rest, double t, Points& x, Eigen::VectorXd* v) const;
};

}  // namespace isochor
