// Heading frame h = (p_x, p_z, theta_y) (Neural3Points, SCA 2022, §4): a frame on the floor at
// (p_x, 0, p_z), Y up, turned by theta_y about Y so that its Z axis is the character's facing
// direction. It moves horizontally with the character's root.
//
//   R_y(theta) = [ c 0 s ]      maps the frame's Z axis (0, 0, 1) to (sin theta, 0, cos theta)
//                [ 0 1 0 ]
//                [-s 0 c ]
//   h1 (x) h2      = (p1 + R_y(theta1) p2, wrap(theta1 + theta2))     composition (paper: (x))
//   inv(h)         = (-R_y(-theta) p, -theta)                          inverse
//   inv(h) (x) p   = R_y(-theta) (p - (p_x, 0, p_z))                   a world point into the frame
//   inv(h) (x) v   = R_y(-theta) v                                     a world vector into the frame
//   inv(h) (x) R   = R_y(-theta) R                                     a world rotation into the frame
//   dh = inv(h_{t-1}) (x) h_t, so that h_t = h_{t-1} (x) dh             heading change (z's delta h)
// theta is kept in (-pi, pi]. Python twin: weights_tool/n3p/layout.py (must stay identical: the
// parity test runs both over whole clips).
#pragma once
#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace sparsebody::features {

// theta_y of a forward direction: the angle about +Y from +Z to its ground projection,
// atan2(f_x, f_z); 0 when it has none (|f_x| + |f_z| <= min_ground: vertical). The one heading
// definition of the library (HeadingFrame::from, yaw_frame; Python twins: weights_tool/n3p/layout.py
// heading_from_forward, weights_tool/lobstr/rotations.py yaw_frame). A float vector keeps float
// arithmetic (min_ground in its type).
template <class Derived>
inline typename Derived::Scalar heading_angle(const Eigen::MatrixBase<Derived>& forward,
                                              typename Derived::Scalar min_ground = typename Derived::Scalar(1e-12)) noexcept {
  using S = typename Derived::Scalar;
  return (std::abs(forward.x()) + std::abs(forward.z()) > min_ground) ? S(std::atan2(forward.x(), forward.z())) : S(0);
}

// R_y(theta) (the matrix in the header comment).
inline Eigen::Matrix3d yaw_rotation(double theta) noexcept {
  const double c = std::cos(theta), s = std::sin(theta);
  Eigen::Matrix3d R;
  R << c, 0, s, 0, 1, 0, -s, 0, c;
  return R;
}

// Rotation about +Y whose Z axis is the ground projection of `forward`: R_y(heading_angle(forward));
// `fallback` when the projection is shorter than 1e-3 (near vertical) or not finite. Built from
// atan2 then cos/sin, it differs from normalising the projection (what the Python twin does) by
// rounding only (~1e-16).
inline Eigen::Matrix3d yaw_frame(const Eigen::Vector3d& forward, const Eigen::Matrix3d& fallback) noexcept {
  const Eigen::Vector3d ground(forward.x(), 0.0, forward.z());
  if (!(ground.norm() >= 1e-3)) return fallback;
  return yaw_rotation(heading_angle(forward));
}

// theta wrapped to (-pi, pi] as atan2(sin, cos) (the same expression as the Python side).
inline double wrap_angle(double a) noexcept { return std::atan2(std::sin(a), std::cos(a)); }

struct HeadingFrame {
  double px = 0, pz = 0, theta = 0;  // (p_x, p_z, theta_y)

  static HeadingFrame identity() noexcept { return {}; }

  // From a floor position (its y is ignored) and a forward direction: theta = heading_angle(f)
  // (atan2(f_x, f_z); a forward along Y, with no ground projection, gives theta = 0).
  static HeadingFrame from(const Eigen::Vector3d& position, const Eigen::Vector3d& forward) noexcept {
    return {position.x(), position.z(), heading_angle(forward)};
  }

  // R_y(theta).
  Eigen::Matrix3d rotation() const noexcept { return yaw_rotation(theta); }

  // h (x) d: composition, d expressed in this frame.
  HeadingFrame operator*(const HeadingFrame& d) const noexcept {
    const double c = std::cos(theta), s = std::sin(theta);
    return {px + (c * d.px + s * d.pz), pz + (-s * d.px + c * d.pz), wrap_angle(theta + d.theta)};
  }
  // inv(h).
  HeadingFrame inverse() const noexcept {
    const double c = std::cos(theta), s = std::sin(theta);
    return {-(c * px - s * pz), -(s * px + c * pz), wrap_angle(-theta)};
  }
  // inv(a) (x) b: the heading change from a to b, expressed in a.
  static HeadingFrame delta(const HeadingFrame& a, const HeadingFrame& b) noexcept {
    const double c = std::cos(a.theta), s = std::sin(a.theta);
    const double dx = b.px - a.px, dz = b.pz - a.pz;
    return {c * dx - s * dz, s * dx + c * dz, wrap_angle(b.theta - a.theta)};
  }

  // inv(h) (x) v for a vector: R_y(-theta) v.
  Eigen::Vector3d vector_to_local(const Eigen::Vector3d& v) const noexcept {
    const double c = std::cos(theta), s = std::sin(theta);
    return {c * v.x() - s * v.z(), v.y(), s * v.x() + c * v.z()};
  }
  // h (x) v for a vector: R_y(theta) v.
  Eigen::Vector3d vector_to_world(const Eigen::Vector3d& v) const noexcept {
    const double c = std::cos(theta), s = std::sin(theta);
    return {c * v.x() + s * v.z(), v.y(), -s * v.x() + c * v.z()};
  }
  // inv(h) (x) p for a point.
  Eigen::Vector3d point_to_local(const Eigen::Vector3d& p) const noexcept {
    return vector_to_local(Eigen::Vector3d(p.x() - px, p.y(), p.z() - pz));
  }
  // h (x) p for a point.
  Eigen::Vector3d point_to_world(const Eigen::Vector3d& p) const noexcept {
    const Eigen::Vector3d w = vector_to_world(p);
    return {w.x() + px, w.y(), w.z() + pz};
  }
  // Rotations: R_y(-theta) R and R_y(theta) R.
  Eigen::Matrix3d rotation_to_local(const Eigen::Matrix3d& R) const noexcept { return rotation().transpose() * R; }
  Eigen::Matrix3d rotation_to_world(const Eigen::Matrix3d& R) const noexcept { return rotation() * R; }

  bool finite() const noexcept { return std::isfinite(px) && std::isfinite(pz) && std::isfinite(theta); }
};

}  // namespace sparsebody::features
