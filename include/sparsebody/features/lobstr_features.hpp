// The 37 LoBSTr input features (paper Appendix 1, eqs. 1-3), one frame at a time.
// Python twin (the reference the parity test compares against): weights_tool/lobstr/features.py.
//
// Reference joint: at the pelvis on the ground (p_ref = (p_x, 0, p_z)), Y up, Z = ground projection
// of the calibrated pelvis forward axis (held from the previous frame when the axis is vertical).
//   v_ref = q_ref,i^-1 (p_ref,i - p_ref,i-1)        w_ref = 6D(q_ref,i-1^-1 q_ref,i)
//   p'    = q_ref^-1 (p - p_ref),  q' = q_ref^-1 q  (each frame in its own reference frame)
//   v     = p'_i - p'_i-1                            w = 6D(q'_i-1^-1 q'_i)
//   x_i   = [v_ref, w_ref, (v, w)_head, (v, w)_left hand, (v, w)_right hand, p_ref,y of the pelvis]
// After reset() the first frame has zero velocities and identity rotations.
#pragma once
#include <array>

#include "sparsebody/pose/rotation6d.hpp"
#include "sparsebody/features/heading_frame.hpp"
#include "sparsebody/trackers/types.hpp"

namespace sparsebody::features {

inline constexpr int kLoBSTrFeatureCount = 37;

class LoBSTrFeatures {
 public:
  void reset() noexcept { have_prev_ = false; }

  // t: calibrated tracker poses (head, left hand, right hand, pelvis), standard scale, floor y = 0.
  template <typename S>
  void compute(const std::array<trackers::PoseD, trackers::kTrackerCount>& t, S* x) noexcept {
    const trackers::PoseD& pel = t[3];
    const Eigen::Matrix3d Rp = pel.orientation.toRotationMatrix();
    const Eigen::Matrix3d Rr = yaw_frame(Rp.col(2), have_prev_ ? Rr_prev_ : Eigen::Matrix3d::Identity());
    const Eigen::Vector3d pr(pel.position.x(), 0.0, pel.position.z());
    const Eigen::Matrix3d RrT = Rr.transpose();
    Eigen::Vector3d pl[3];
    Eigen::Matrix3d Rl[3];
    for (int k = 0; k < 3; ++k) {
      pl[k] = RrT * (t[k].position - pr);
      Rl[k] = RrT * t[k].orientation.toRotationMatrix();
    }
    if (!have_prev_) {
      Rr_prev_ = Rr;
      pr_prev_ = pr;
      for (int k = 0; k < 3; ++k) pl_prev_[k] = pl[k], Rl_prev_[k] = Rl[k];
      have_prev_ = true;
    }
    const Eigen::Vector3d vref = RrT * (pr - pr_prev_);
    for (int i = 0; i < 3; ++i) x[i] = static_cast<S>(vref[i]);
    pose::to6d<S>(Rr_prev_.transpose() * Rr, x + 3);
    for (int k = 0; k < 3; ++k) {
      S* o = x + 9 + 9 * k;
      const Eigen::Vector3d v = pl[k] - pl_prev_[k];
      for (int i = 0; i < 3; ++i) o[i] = static_cast<S>(v[i]);
      pose::to6d<S>(Rl_prev_[k].transpose() * Rl[k], o + 3);
      pl_prev_[k] = pl[k];
      Rl_prev_[k] = Rl[k];
    }
    x[36] = static_cast<S>(pel.position.y());
    Rr_prev_ = Rr;
    pr_prev_ = pr;
  }

  // The current reference frame (valid after compute).
  const Eigen::Matrix3d& reference_rotation() const noexcept { return Rr_prev_; }

 private:
  bool have_prev_ = false;
  Eigen::Matrix3d Rr_prev_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d pr_prev_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d pl_prev_[3];
  Eigen::Matrix3d Rl_prev_[3];
};

}  // namespace sparsebody::features
