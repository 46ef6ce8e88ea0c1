// Rigid transforms for the DEM: a unit quaternion (Hamilton convention, w first) and a pose.
// A pose maps body coordinates to world coordinates: x_world = position + Rotate(orientation,
// x_body). Public header of the dem module.
#pragma once

#include <cmath>

#include "dem/vec3.h"

namespace dem {

struct Quat {
  double w = 1, x = 0, y = 0, z = 0;
};

inline Quat operator*(const Quat& a, const Quat& b) {
  return {
      a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
      a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}
inline Quat Conjugate(const Quat& q) { return {q.w, -q.x, -q.y, -q.z}; }
inline Quat Normalized(const Quat& q) {
  const double n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  return {q.w / n, q.x / n, q.y / n, q.z / n};
}
// Rotation by `angle` [rad] about the unit vector `axis`.
inline Quat AxisAngle(const Vec3& axis, double angle) {
  const double s = std::sin(0.5 * angle);
  return {std::cos(0.5 * angle), s * axis.x, s * axis.y, s * axis.z};
}
// q v q*, written out (no temporaries).
inline Vec3 Rotate(const Quat& q, const Vec3& v) {
  const Vec3 u{q.x, q.y, q.z};
  const Vec3 t = 2.0 * Cross(u, v);
  return v + q.w * t + Cross(u, t);
}
inline Vec3 RotateInverse(const Quat& q, const Vec3& v) { return Rotate(Conjugate(q), v); }

struct Pose {
  Vec3 position;     // body origin in world [m]
  Quat orientation;  // body -> world rotation
};
inline Vec3 Apply(const Pose& p, const Vec3& x_body) {
  return p.position + Rotate(p.orientation, x_body);
}
inline Vec3 ApplyInverse(const Pose& p, const Vec3& x_world) {
  return RotateInverse(p.orientation, x_world - p.position);
}

}  // namespace dem
