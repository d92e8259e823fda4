// 6D rotation representation (Zhou et al. 2019) in the LoBSTr layout: the rotated forward (Z) axis
// then the rotated up (Y) axis, i.e. columns 2 and 1 of R (paper §3: "6-DoF with forward (Z-axis)
// and up (Y-axis) vectors"). Weights files state it as meta.rotation = {"representation": "6d",
// "layout": "columns", "columns": [2, 1]}. Python twin: weights_tool/lobstr/rotations.py.
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace sparsebody::pose {

// d[0..2] = R e_z, d[3..5] = R e_y.
template <typename S, typename D>
inline void to6d(const Eigen::Matrix3d& R, D* d) noexcept {
  for (int i = 0; i < 3; ++i) {
    d[i] = static_cast<S>(R(i, 2));
    d[3 + i] = static_cast<S>(R(i, 1));
  }
}

// Gram-Schmidt with the forward axis kept exactly: z = a/|a|, x = (b x z)/|b x z|, y = z x x.
// Degenerate input (|a| or |b x z| ~ 0) gives the identity rather than NaN.
template <typename S>
inline Eigen::Matrix3d from6d(const S* d) noexcept {
  Eigen::Vector3d a(d[0], d[1], d[2]), b(d[3], d[4], d[5]);
  const double na = a.norm();
  if (!(na > 1e-9)) return Eigen::Matrix3d::Identity();
  const Eigen::Vector3d z = a / na;
  Eigen::Vector3d x = b.cross(z);
  const double nx = x.norm();
  if (!(nx > 1e-9)) return Eigen::Matrix3d::Identity();
  x /= nx;
  Eigen::Matrix3d R;
  R.col(0) = x;
  R.col(1) = z.cross(x);
  R.col(2) = z;
  return R;
}

}  // namespace sparsebody::pose
