// Tracker input types, OpenXR conventions: a pose is a position in metres and an orientation
// quaternion stored (x, y, z, w) (as XrPosef); right-handed, +X right, +Y up, -Z forward, origin on
// the floor (XR_REFERENCE_SPACE_TYPE_STAGE). A frame holds a timestamp (seconds, any origin,
// increasing) and, per tracker, a pose and a validity flag (the runtime's
// XR_SPACE_LOCATION_POSITION_VALID_BIT and ORIENTATION_VALID_BIT both set).
#pragma once
#include <array>
#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace sparsebody::trackers {

struct Quatf {
  float x = 0, y = 0, z = 0, w = 1;
};
struct Vec3f {
  float x = 0, y = 0, z = 0;
};
struct Posef {
  Quatf orientation;
  Vec3f position;
};

enum class Tracker : int { Head = 0, LeftHand = 1, RightHand = 2, Pelvis = 3 };
inline constexpr int kTrackerCount = 4;
inline const char* tracker_name(int k) noexcept {
  static const char* n[] = {"head", "left_hand", "right_hand", "pelvis"};
  return n[k];
}

struct TrackerFrame {
  double time = 0;                              // seconds
  std::array<Posef, kTrackerCount> pose{};
  std::array<bool, kTrackerCount> valid{};      // false: ignore pose (tracking lost, not worn)

  Posef& operator[](Tracker t) noexcept { return pose[static_cast<int>(t)]; }
  const Posef& operator[](Tracker t) const noexcept { return pose[static_cast<int>(t)]; }
};

// Conversions to the double-precision Eigen types used inside the pipeline.
inline Eigen::Vector3d to_eigen(const Vec3f& p) noexcept { return {p.x, p.y, p.z}; }
inline Eigen::Quaterniond to_eigen(const Quatf& q) noexcept { return Eigen::Quaterniond(q.w, q.x, q.y, q.z); }
inline Vec3f to_xr(const Eigen::Vector3d& p) noexcept {
  return {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())};
}
inline Quatf to_xr(const Eigen::Quaterniond& q) noexcept {
  return {static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z()), static_cast<float>(q.w())};
}

// A tracker pose in double precision (what the pipeline works with after checks).
struct PoseD {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
};

// A recorded pose as a usable one: finite, with a quaternion whose norm is within quat_tolerance of
// 1 (renormalised into out). False (out untouched) otherwise. The sanitizer's and the recentre
// detector's test of a pose.
inline bool checked_pose(const Posef& in, double quat_tolerance, PoseD& out) noexcept {
  const Eigen::Vector3d p = to_eigen(in.position);
  const Eigen::Quaterniond q = to_eigen(in.orientation);
  if (!p.allFinite() || !q.coeffs().allFinite()) return false;
  const double n = q.norm();
  if (std::abs(n - 1.0) > quat_tolerance) return false;
  out.position = p;
  out.orientation = Eigen::Quaterniond(q.coeffs() / n);
  return true;
}

}  // namespace sparsebody::trackers
