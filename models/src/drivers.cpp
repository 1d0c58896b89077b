#include "isochor/models/drivers.hpp"

#include <algorithm>
#include <Eigen/Geometry>
#include <cmath>

#include "isochor/base/error.hpp"

namespace isochor {

int key_segment(const std::vector<double>& times, double t, double& s) {
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
  if (kind == Kind::keyframes_cubic) {
    Eigen::Vector3d value, rate;
    cubic_keys(times, values, t, value, rate);
    return value;
  }
  double s;
  const int i = key_segment(times, t, s);
  if (i == -1) return values.front();
  if (i == -2) return values.back();
  return (1 - s) * values[i] + s * values[i + 1];
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
  if (kind == Kind::keyframes_cubic) {
    Eigen::Vector3d value, rate;
    cubic_keys(times, values, t, value, rate);
    return rate;
  }
  double s;
  const int i = key_segment(times, t, s);
  if (i < 0) return Eigen::Vector3d::Zero();
  return (values[i + 1] - values[i]) / (times[i + 1] - times[i]);
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
