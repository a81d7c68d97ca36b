// Small rigid-body helpers: skew matrices and Euler parameters (unit quaternions).
//
// Euler parameters p = (e0, e1, e2, e3) are stored as 4-vectors with the scalar e0 first. A(p) is the
// rotation from the body frame to the world frame: v_in_world = A(p) * v_in_body.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace rail::vehicle {

using Vector3 = Eigen::Vector3d;
using Vector4 = Eigen::Vector4d;
using Matrix3 = Eigen::Matrix3d;

// Skew-symmetric matrix a~ such that a~ * b = a x b.
inline Matrix3 skew(const Vector3& a) {
  Matrix3 s;
  s << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
  return s;
}

// Rotation matrix A (body to world) of Euler parameters p; p is normalised first.
inline Matrix3 rotationFromEulerParameters(const Vector4& p_raw) {
  const Vector4 p = p_raw / p_raw.norm();
  const double e0 = p[0];
  const Vector3 e = p.tail<3>();
  return (e0 * e0 - e.squaredNorm()) * Matrix3::Identity() + 2.0 * e * e.transpose() + 2.0 * e0 * skew(e);
}

// Quaternion product a (x) b, scalar first.
inline Vector4 quaternionProduct(const Vector4& a, const Vector4& b) {
  Vector4 c;
  c[0] = a[0] * b[0] - a.tail<3>().dot(b.tail<3>());
  c.tail<3>() = a[0] * b.tail<3>() + b[0] * a.tail<3>() + a.tail<3>().cross(b.tail<3>());
  return c;
}

// Euler parameters of a rotation by the vector theta (axis * angle, rad).
inline Vector4 eulerParametersFromRotationVector(const Vector3& theta) {
  const double angle = theta.norm();
  Vector4 p;
  if (angle < 1e-12) {
    p[0] = 1.0;
    p.tail<3>() = 0.5 * theta;
    return p / p.norm();
  }
  p[0] = std::cos(0.5 * angle);
  p.tail<3>() = std::sin(0.5 * angle) / angle * theta;
  return p;
}

// Euler parameters of a rotation matrix (body to world).
inline Vector4 eulerParametersFromRotation(const Matrix3& A) {
  // Shepperd's method: pick the largest of the four squared components for stability.
  const double t = A.trace();
  Vector4 p;
  if (t >= A(0, 0) && t >= A(1, 1) && t >= A(2, 2)) {
    const double s = 2.0 * std::sqrt(1.0 + t);
    p << 0.25 * s, (A(2, 1) - A(1, 2)) / s, (A(0, 2) - A(2, 0)) / s, (A(1, 0) - A(0, 1)) / s;
  } else if (A(0, 0) >= A(1, 1) && A(0, 0) >= A(2, 2)) {
    const double s = 2.0 * std::sqrt(1.0 + 2.0 * A(0, 0) - t);
    p << (A(2, 1) - A(1, 2)) / s, 0.25 * s, (A(0, 1) + A(1, 0)) / s, (A(0, 2) + A(2, 0)) / s;
  } else if (A(1, 1) >= A(2, 2)) {
    const double s = 2.0 * std::sqrt(1.0 + 2.0 * A(1, 1) - t);
    p << (A(0, 2) - A(2, 0)) / s, (A(0, 1) + A(1, 0)) / s, 0.25 * s, (A(1, 2) + A(2, 1)) / s;
  } else {
    const double s = 2.0 * std::sqrt(1.0 + 2.0 * A(2, 2) - t);
    p << (A(1, 0) - A(0, 1)) / s, (A(0, 2) + A(2, 0)) / s, (A(1, 2) + A(2, 1)) / s, 0.25 * s;
  }
  if (p[0] < 0.0) p = -p;
  return p / p.norm();
}

// Rotation vector (axis * angle, rad, |angle| <= pi) of a rotation matrix.
inline Vector3 rotationVectorFromRotation(const Matrix3& R) {
  const Vector4 p = eulerParametersFromRotation(R);  // p[0] >= 0
  const double s = p.tail<3>().norm();
  if (s < 1e-12) return 2.0 * p.tail<3>();
  const double angle = 2.0 * std::atan2(s, p[0]);
  return angle / s * p.tail<3>();
}

}  // namespace rail::vehicle
