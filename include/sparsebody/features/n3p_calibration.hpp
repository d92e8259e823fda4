// Neural3Points calibration (SCA 2022, §7): the predictor's input is the pose of the user's head
// and wrists, not of the devices. A thin layer over the shared calibration (features/calibration.hpp:
// o_k, d_k in the calibrated frame, floor, s = standard head-joint height / the user's):
//   - by default d_k are the device model's (features/device_model.hpp): the eye offset for the
//     headset, the grip offsets for the controllers;
//   - from a T-pose (when the user makes one; never required) the wrist offsets are measured: the
//     wrists sit where the standard skeleton's T-pose puts them relative to the head joint (arms
//     straight out sideways, in the user's size), so d_k = R_cal,k^-1 (p_k - p_wrist_k), with
//     R_cal,k = the facing frame at that frame. The head offset stays the eye offset.
// Calibrated joint pose of tracker k: position s (p_k - floor y - R_cal,k d_k), orientation R_cal,k.
#pragma once
#include <array>
#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "sparsebody/features/calibration.hpp"
#include "sparsebody/features/device_model.hpp"
#include "sparsebody/features/n3p_tracker_input.hpp"
#include "sparsebody/pose/skeleton.hpp"
#include "sparsebody/features/heading_frame.hpp"
#include "sparsebody/trackers/types.hpp"

namespace sparsebody::features::n3p {

// Wrist positions of the skeleton's T-pose relative to its head joint, in the body's facing frame
// (X left, Y up, Z forward), skeleton units. Needs joints named Chest, Neck, Head, Shoulder_L,
// UpperArm_L, LowerArm_L, Hand_L and the _R twins (the standard skeleton); zero when absent.
inline std::array<Eigen::Vector3d, 2> tpose_wrists(const pose::Skeleton& s) {
  std::array<Eigen::Vector3d, 2> out{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  const int chest = s.find("Chest"), neck = s.find("Neck"), head = s.find("Head");
  if (chest < 0 || neck < 0 || head < 0) return out;
  const Eigen::Vector3d spine_dir = s.offsets[neck].normalized();  // the spine's axis in the chest frame
  const double head_up = s.offsets[neck].norm() + s.offsets[head].norm();
  const char* names[2][4] = {{"Shoulder_L", "UpperArm_L", "LowerArm_L", "Hand_L"},
                             {"Shoulder_R", "UpperArm_R", "LowerArm_R", "Hand_R"}};
  for (int side = 0; side < 2; ++side) {
    int j[4];
    for (int i = 0; i < 4; ++i) j[i] = s.find(names[side][i]);
    if (j[0] < 0 || j[1] < 0 || j[2] < 0 || j[3] < 0) continue;
    const Eigen::Vector3d sh = s.offsets[j[0]];
    const double up = sh.dot(spine_dir);
    const double lateral = (sh - up * spine_dir).norm() + s.offsets[j[1]].norm() + s.offsets[j[2]].norm() + s.offsets[j[3]].norm();
    out[side] = Eigen::Vector3d(side == 0 ? lateral : -lateral, up - head_up, 0.0);
  }
  return out;
}

struct N3PCalibration {
  Calibration base;            // o_k, d_k, floor, s (the shared calibration)
  bool hand_offsets = false;   // whether d_1, d_2 were measured from a plausible T-pose

  // Before calibration (half-turn offsets, the device offsets, s = 1).
  static N3PCalibration uncalibrated(const DeviceModel& d) noexcept {
    N3PCalibration c;
    c.base = Calibration::uncalibrated(d);
    return c;
  }

  // From a T-pose frame. False (unchanged) when the headset part cannot be used. The wrist offsets
  // are measured only when both controllers are valid and within 0.5 m of where a T-pose puts the
  // wrists (otherwise they are the device model's grip offsets, hand_offsets false).
  bool from_tpose(const trackers::TrackerFrame& f, const pose::Skeleton& skeleton, double standard_hips_height,
                  double standard_head_height, const DeviceModel& devices = DeviceModel{}) noexcept {
    N3PCalibration c;
    // the pelvis tracker plays no part here: calibrate orientations and scale from the headset
    trackers::TrackerFrame g = f;
    g.valid[3] = false;
    if (!c.base.from_tpose(g, standard_hips_height, standard_head_height, devices, ScaleFrom::Head)) return false;
    const Eigen::Matrix3d yaw = Calibration::facing(trackers::to_eigen(f.pose[0].orientation));
    const Eigen::Vector3d head = trackers::to_eigen(f.pose[0].position) - yaw * devices.eye;  // the head joint
    const std::array<Eigen::Vector3d, 2> w = tpose_wrists(skeleton);
    bool ok = f.valid[1] && f.valid[2];
    std::array<Eigen::Vector3d, 2> d;
    for (int k = 1; k < 3 && ok; ++k) {
      const Eigen::Vector3d p = trackers::to_eigen(f.pose[k].position);
      const Eigen::Vector3d wrist = head + yaw * (w[k - 1] / c.base.scale);
      d[k - 1] = yaw.transpose() * (p - wrist);  // R_cal,k = yaw at this frame
      ok = p.allFinite() && trackers::to_eigen(f.pose[k].orientation).coeffs().allFinite() && d[k - 1].norm() < 0.5;  // else: not a T-pose
    }
    if (ok) c.base.position_offset[1] = d[0], c.base.position_offset[2] = d[1];
    c.hand_offsets = ok;
    *this = c;
    return true;
  }

  // Calibrated joint sample of tracker k (k < 3) from a device pose.
  TrackerSample apply(int k, const trackers::PoseD& device) const noexcept {
    const trackers::PoseD j = base.apply(k, device);
    return TrackerSample::from(j.position, j.orientation.toRotationMatrix());
  }
};

}  // namespace sparsebody::features::n3p
