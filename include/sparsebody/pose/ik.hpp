// Inverse kinematics used by the pipelines: aim frames and the analytic two-bone solver (arms,
// legs). Positions in metres; rotations are world rotations unless said otherwise.
#pragma once
#include <algorithm>
#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace sparsebody::pose {

// Orthonormal frame whose first axis is a and whose second lies in the (a, b) plane.
inline Eigen::Matrix3d frame_from(const Eigen::Vector3d& a, const Eigen::Vector3d& b) noexcept {
  const Eigen::Vector3d x = a.normalized();
  Eigen::Vector3d y = b - b.dot(x) * x;
  if (y.norm() < 1e-9) {  // b parallel to a: any perpendicular
    y = std::abs(x.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    y -= y.dot(x) * x;
  }
  y.normalize();
  Eigen::Matrix3d F;
  F.col(0) = x;
  F.col(1) = y;
  F.col(2) = x.cross(y);
  return F;
}

// World rotation R that maps the joint-local axis `a_local` onto `a_world` exactly and brings
// `b_local` as close as possible to `b_world` (an "aim" constraint with an up/twist vector).
inline Eigen::Quaterniond aim(const Eigen::Vector3d& a_local, const Eigen::Vector3d& b_local,
                              const Eigen::Vector3d& a_world, const Eigen::Vector3d& b_world) noexcept {
  return Eigen::Quaterniond(frame_from(a_world, b_world) * frame_from(a_local, b_local).transpose());
}

// Two-bone IK on positions: a (root, fixed), b (middle), c (end) with bone lengths |b - a| and
// |c - b| kept; the end goes to `target` (clamped to the reachable shell) and the middle bends
// towards `pole` (the current bend is used when the pole is along the reach line).
// Law of cosines: cos(alpha) = (l1^2 + d^2 - l2^2) / (2 l1 d), alpha at a between reach and bone 1.
inline void two_bone(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                     const Eigen::Vector3d& target, const Eigen::Vector3d& pole, Eigen::Vector3d& b_out,
                     Eigen::Vector3d& c_out) noexcept {
  const double l1 = (b - a).norm(), l2 = (c - b).norm();
  Eigen::Vector3d reach = target - a;
  double d = reach.norm();
  const Eigen::Vector3d dir = d > 1e-9 ? Eigen::Vector3d(reach / d) : Eigen::Vector3d((c - a).normalized());
  d = std::clamp(d, std::abs(l1 - l2) + 1e-6, l1 + l2 - 1e-6);
  Eigen::Vector3d n = pole - pole.dot(dir) * dir;
  if (n.norm() < 1e-6) n = (b - a) - (b - a).dot(dir) * dir;
  if (n.norm() < 1e-9) n = std::abs(dir.y()) < 0.9 ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitZ(), n -= n.dot(dir) * dir;
  n.normalize();
  const double ca = std::clamp((l1 * l1 + d * d - l2 * l2) / (2 * l1 * d), -1.0, 1.0);
  b_out = a + l1 * (ca * dir + std::sqrt(std::max(0.0, 1 - ca * ca)) * n);
  c_out = a + d * dir;
}

// Shortest rotation taking direction u to direction v.
inline Eigen::Quaterniond swing(const Eigen::Vector3d& u, const Eigen::Vector3d& v) noexcept {
  return Eigen::Quaterniond::FromTwoVectors(u, v);
}

}  // namespace sparsebody::pose
