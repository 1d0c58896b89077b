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

// Keyframe segment containing t and the local parameter s in [0, 1]: -1 before the first key
// (s = 0), -2 after the last (s = 1).
int key_segment(const std::vector<double>& times, double t, double& s);

// The cubic Hermite through keys (t_k, v_k) with Catmull-Rom tangents, zero at the first and last
// keys, where the value is then held: C^1 everywhere (a driven velocity that jumps stalls IDA).
// Its value and rate at t, for any vector type (3 displacements, 4 quaternion components).
template <class V>
void cubic_keys(const std::vector<double>& times, const std::vector<V>& values, double t, V& value, V& rate) {
  double s;
  const int i = key_segment(times, t, s);
  if (i < 0) {
    value = i == -1 ? values.front() : values.back();
    rate = V::Zero();
    return;
  }
  const int n = static_cast<int>(times.size());
  auto tangent = [&](int k) -> V {
    if (k == 0 || k == n - 1) return V::Zero();
    return (values[k + 1] - values[k - 1]) / (times[k + 1] - times[k - 1]);
  };
  const double h = times[i + 1] - times[i];
  const V m0 = tangent(i), m1 = tangent(i + 1);
  value = (2 * s * s * s - 3 * s * s + 1) * values[i] + (s * s * s - 2 * s * s + s) * h * m0 +
          (-2 * s * s * s + 3 * s * s) * values[i + 1] + (s * s * s - s * s) * h * m1;
  rate = ((6 * s * s - 6 * s) * values[i] + (-6 * s * s + 6 * s) * values[i + 1]) / h + (3 * s * s - 4 * s + 1) * m0 +
         (3 * s * s - 2 * s) * m1;
}

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
