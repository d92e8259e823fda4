// Calibration (paper §4.2): per-tracker rotational offsets and a height scale to the standard
// skeleton, found from one frame of the user standing upright in a T-pose, facing forward.
//   offsets: o_k = q_k^-1 Yaw(headset forward), so that at calibration every calibrated tracker
//            q_k o_k has the body's facing frame (X left, Y up, Z forward), the convention the
//            network was trained with (recordings/tracker_synthesis.hpp);
//   scale:   s = standing pelvis height of the standard skeleton / the user's (headset heights when
//            no pelvis tracker). Positions are multiplied by s before the features, and the output
//            pose is divided by s to match the user's size.
#pragma once
#include <array>

#include "sparsebody/features/heading_frame.hpp"
#include "sparsebody/trackers/types.hpp"

namespace sparsebody::features {

struct Calibration {
  std::array<Eigen::Quaterniond, trackers::kTrackerCount> offset{
      Eigen::Quaterniond::Identity(), Eigen::Quaterniond::Identity(), Eigen::Quaterniond::Identity(),
      Eigen::Quaterniond::Identity()};
  double scale = 1.0;  // s: user -> standard skeleton

  // From a T-pose frame (head must be valid). OpenXR: the headset looks along its -Z axis.
  // Returns false (calibration unchanged) when the frame cannot be used.
  bool from_tpose(const trackers::TrackerFrame& f, double standard_hips_height, double standard_head_height) noexcept {
    using trackers::to_eigen;
    if (!f.valid[0]) return false;
    const Eigen::Quaterniond qh = to_eigen(f.pose[0].orientation).normalized();
    const Eigen::Vector3d fwd = -(qh * Eigen::Vector3d::UnitZ());
    const Eigen::Matrix3d yaw = yaw_frame(fwd, Eigen::Matrix3d::Identity());
    if (!to_eigen(f.pose[0].position).allFinite()) return false;
    Calibration c;
    for (int k = 0; k < trackers::kTrackerCount; ++k) {
      if (!f.valid[k]) continue;
      c.offset[k] = Eigen::Quaterniond(to_eigen(f.pose[k].orientation).normalized().toRotationMatrix().transpose() * yaw);
    }
    const double hp = f.pose[3].position.y, hh = f.pose[0].position.y;
    if (f.valid[3] && hp > 0.3) c.scale = standard_hips_height / hp;
    else if (hh > 0.5) c.scale = standard_head_height / hh;
    else return false;
    *this = c;
    return true;
  }

  // Calibrated tracker poses in the standard skeleton's scale: (s p, q o).
  void apply(const std::array<trackers::PoseD, trackers::kTrackerCount>& in,
             std::array<trackers::PoseD, trackers::kTrackerCount>& out) const noexcept {
    for (int k = 0; k < trackers::kTrackerCount; ++k) {
      out[k].position = scale * in[k].position;
      out[k].orientation = in[k].orientation * offset[k];
    }
  }
};

}  // namespace sparsebody::features
