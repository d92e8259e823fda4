// A foot pinned at its toe base that the leg cannot reach: turn it about the toe.
//
// A toe pin (Neural3Points direct mode's N3PConfig::Pin::Toe) puts the ankle at
//   ankle = toe - R t        (R: the foot joint's world rotation, t: the toe's offset in the foot frame)
// so the ankle lies on a circle of radius |t| about the pinned toe. When the hip has moved so far
// that the ankle R asks for is beyond the leg's reach, a real foot rolls over its toe: the heel
// rises when the hip is above or ahead of the foot (a leg straightening over it, a trailing leg at
// the end of its stance), the heel comes down when the hip is behind it. roll_foot_into_reach turns R about the
// foot's lateral axis through the toe by the least angle that brings the ankle within reach, the
// ankle's elevation above the toe kept within [0, 80 deg]:
//   ankle(theta) = toe + r (cos(theta) u1 + sin(theta) u2),  u1 = (toe -> ankle) / r,  u2 = a x u1,
//   |hip - ankle(theta)|^2 = |q|^2 + r^2 - 2 r (q . u(theta)),  q = hip - toe,
// so the ankle is in reach where q . u(theta) = |q_plane| cos(theta - phi) >= k,
// k = (|q|^2 + r^2 - reach^2) / (2 r): an interval of theta about phi, whose point nearest 0 is taken.
// Without the roll, such a pin slid or was released and its toe slid with it. The direct mode rolls
// only feet held while the user stands still (avatar/n3p_direct.hpp).
// lower_heel is the other way: a foot held heel-up (a stop caught the rear foot at its push-off)
// comes down about the same axis towards the standing foot's elevation; the roll then raises it
// again as far as the leg's reach needs.
#pragma once
#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace sparsebody::pose {

// The highest elevation of an ankle above its toe a foot may have (80 deg: beyond, no foot).
inline constexpr double kMaxAnkleElevation = 1.3962634015954636;

// The elevation (rad) of toe -> ankle `e` above the horizontal; 0 for a zero vector.
inline double ankle_elevation(const Eigen::Vector3d& e) noexcept {
  const double r = e.norm();
  return r > 0 ? std::asin(std::clamp(e.y() / r, -1.0, 1.0)) : 0.0;
}

namespace detail {
// A foot's pitch about its toe: toe -> ankle e = -(foot t), its length r, and the unit horizontal
// lateral axis a about which a positive turn raises the ankle. False for a degenerate (zero-length
// or vertical) foot.
inline bool foot_pitch(const Eigen::Quaterniond& foot, const Eigen::Vector3d& t, Eigen::Vector3d& e, double& r,
                       Eigen::Vector3d& a) noexcept {
  e = -(foot * t);
  r = e.norm();
  if (!(r > 1e-9)) return false;
  a = e.cross(Eigen::Vector3d::UnitY());
  if (!(a.norm() > 1e-9 * r)) return false;
  a.normalize();
  return true;
}
}  // namespace detail

// `foot` turned about its lateral axis through `toe` so that its ankle (toe - foot * t) is within
// 0.999 `reach` of `hip`; unchanged when it is in reach already or for a degenerate (vertical or
// zero-length) foot. When no turn of at most `max_roll` radians within the elevation bounds reaches,
// the allowed turn that brings the ankle nearest the hip (unchanged if none brings it nearer).
// Never non-finite for finite input.
inline Eigen::Quaterniond roll_foot_into_reach(const Eigen::Quaterniond& foot, const Eigen::Vector3d& toe,
                                               const Eigen::Vector3d& t, const Eigen::Vector3d& hip, double reach,
                                               double max_roll) noexcept {
  Eigen::Vector3d e, a;  // toe -> ankle, the foot's lateral axis
  double r = 0;
  const Eigen::Vector3d q = hip - toe;
  const double want = 0.999 * reach;
  if (!((q + foot * t).norm() > want) || !detail::foot_pitch(foot, t, e, r, a)) return foot;
  const Eigen::Vector3d u1 = e / r, u2 = a.cross(u1);
  const double p1 = q.dot(u1), p2 = q.dot(u2), pv = std::hypot(p1, p2);
  const double k = (q.squaredNorm() + r * r - want * want) / (2 * r);
  const double phi = std::atan2(p2, p1);
  const double alpha = k < pv ? std::acos(std::max(-1.0, k / pv)) : -1.0;  // -1: beyond reach whatever the roll
  // theta > 0 raises the ankle (heel up): the ankle's elevation above the toe, beta + theta, stays
  // within [0, 80 deg] (a heel below its toe, or a foot turned over, is no foot)
  const double beta = ankle_elevation(e);
  const double bl = std::max(-max_roll, -beta), bh = std::min(max_roll, kMaxAnkleElevation - beta);  // allowed turns
  // theta - phi within [-alpha, alpha] modulo 2 pi: the interval and its neighbours a turn away
  double theta = std::numeric_limits<double>::infinity();
  for (int turn = -1; turn <= 1 && alpha >= 0; ++turn) {
    const double c = phi + 2 * M_PI * turn;
    const double lo = std::max(c - alpha, bl), hi = std::min(c + alpha, bh);
    if (lo <= hi && std::abs(std::clamp(0.0, lo, hi)) < std::abs(theta)) theta = std::clamp(0.0, lo, hi);
  }
  if (!std::isfinite(theta)) {
    // no allowed turn reaches: turn as far as allowed towards phi (where the ankle is nearest the
    // hip), so that what the caller does next (a held pin slides into reach) is as small as it can
    // be and continuous from the frame before
    if (!(bl <= bh)) return foot;
    theta = std::clamp(std::remainder(phi, 2 * M_PI), bl, bh);
    if (!(q.squaredNorm() + r * r - 2 * r * (p1 * std::cos(theta) + p2 * std::sin(theta)) < (q - e).squaredNorm())) return foot;
  }
  return (Eigen::AngleAxisd(theta, a) * foot).normalized();
}

// `foot` turned about its lateral axis through the toe so that the ankle's elevation above the toe
// (the angle of toe -> ankle, -(foot * t), above the horizontal) comes down towards `elevation` by at
// most `max_turn` radians; unchanged when it is at or below `elevation`, or for a degenerate foot.
inline Eigen::Quaterniond lower_heel(const Eigen::Quaterniond& foot, const Eigen::Vector3d& t, double elevation,
                                     double max_turn) noexcept {
  Eigen::Vector3d e, a;
  double r = 0;
  if (!detail::foot_pitch(foot, t, e, r, a)) return foot;
  const double turn = std::min(ankle_elevation(e) - elevation, max_turn);
  if (!(turn > 0)) return foot;
  return (Eigen::AngleAxisd(-turn, a) * foot).normalized();
}

}  // namespace sparsebody::pose
