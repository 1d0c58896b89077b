#include "isochor/models/drivers.hpp"

#include <algorithm>
#include <Eigen/Geometry>
#include <cmath>

#include "isochor/base/error.hpp"

namespace isochor {

namespace {
// Keyframe segment containing t (clamped to the ends) and the local parameter s in [0, 1].
int segment(const std::vector<double>& times, double t, double& s) {
  const int n = static_cast<int>(times.size());
  if (t <= times.front()) {
    s = 0;
    return -1;
  }
  if (t >= times.back()) {
    s = 1;
    return -2;
  }
  const int i = static_cast<int>(std::upper_bound(times.begin(), times.end(), t) - times.begin()) - 1;
  s = (t - times[i]) / (times[i + 1] - times[i]);
  return std::min(i, n - 2);
}
// Catmull-Rom tangent at keyframe k; zero at the first and last keys, where the value is then
// held, so that the motion is C^1 at the ends too (a driven velocity that jumps stalls IDA).
Eigen::Vector3d tangent(const std::vector<double>& times, const std::vector<Eigen::Vector3d>& values, int k) {
  const int n = static_cast<int>(times.size());
  if (k == 0 || k == n - 1) return Eigen::Vector3d::Zero();
  return (values[k + 1] - values[k - 1]) / (times[k + 1] - times[k - 1]);
}
}  // namespace

Eigen::Vector3d Driver::displacement(double t) const {
  switch (kind) {
    case Kind::fixed:
      return Eigen::Vector3d::Zero();
    case Kind::ramp:
      return vector * std::clamp((t - t0) / (t1 - t0), 0.0, 1.0);
    case Kind::sinusoid:
      return vector * std::sin(2 * M_PI * frequency * t + phase);
    default:
      break;
  }
  double s;
  const int i = segment(times, t, s);
  if (i == -1) return values.front();
  if (i == -2) return values.back();
  if (kind == Kind::keyframes_linear) return (1 - s) * values[i] + s * values[i + 1];
  // Cubic Hermite on [t_i, t_i+1] with Catmull-Rom tangents (zero at the ends).
  const double h = times[i + 1] - times[i];
  const double h00 = 2 * s * s * s - 3 * s * s + 1, h10 = s * s * s - 2 * s * s + s, h01 = -2 * s * s * s + 3 * s * s,
               h11 = s * s * s - s * s;
  return h00 * values[i] + h10 * h * tangent(times, values, i) + h01 * values[i + 1] +
         h11 * h * tangent(times, values, i + 1);
}

Eigen::Vector3d Driver::velocity(double t) const {
  switch (kind) {
    case Kind::fixed:
      return Eigen::Vector3d::Zero();
    case Kind::ramp:
      return (t > t0 && t < t1) ? Eigen::Vector3d(vector / (t1 - t0)) : Eigen::Vector3d::Zero();
    case Kind::sinusoid:
      return vector * 2 * M_PI * frequency * std::cos(2 * M_PI * frequency * t + phase);
    default:
      break;
  }
  double s;
  const int i = segment(times, t, s);
  if (i < 0) return Eigen::Vector3d::Zero();
  const double h = times[i + 1] - times[i];
  if (kind == Kind::keyframes_linear) return (values[i + 1] - values[i]) / h;
  const double d00 = 6 * s * s - 6 * s, d10 = 3 * s * s - 4 * s + 1, d01 = -6 * s * s + 6 * s, d11 = 3 * s * s - 2 * s;
  return (d00 * values[i] + d01 * values[i + 1]) / h + d10 * tangent(times, values, i) +
         d11 * tangent(times, values, i + 1);
}

void Driver::breakpoints(std::vector<double>& out) const {
  switch (kind) {
    case Kind::ramp:
      out.insert(out.end(), {t0, t1});
      break;
    case Kind::keyframes_linear:
      out.insert(out.end(), times.begin(), times.end());
      break;
    case Kind::keyframes_cubic:
      if (!times.empty()) out.insert(out.end(), {times.front(), times.back()});
      break;
    default:
      break;
  }
}

void Driver::apply(const Points& rest, double t, Points& x, Eigen::VectorXd* v) const {
  if (rotation) {
    const double theta = displacement(t).x(), omega = v ? velocity(t).x() : 0.0;
    const Eigen::Matrix3d R = Eigen::AngleAxisd(theta, axis).toRotationMatrix();
    for (int n : nodes) {
      x.col(n) = center + R * (rest.col(n) - center);
      if (v) v->segment<3>(3 * n) = omega * axis.cross(x.col(n) - center);
    }
    return;
  }
  const Eigen::Vector3d u = displacement(t);
  const Eigen::Vector3d du = v ? velocity(t) : Eigen::Vector3d::Zero();
  for (int n : nodes) {
    x.col(n) = rest.col(n) + u;
    if (v) v->segment<3>(3 * n) = du;
  }
}

}  // namespace isochor
