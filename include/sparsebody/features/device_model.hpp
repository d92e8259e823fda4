// Where real devices sit relative to the joints the networks were trained on (mocap head joint,
// wrists, hips). The networks see joints; a headset reports the view pose between the eyes and a
// controller its grip, so the pipelines subtract these offsets before anything else.
//
// Offsets are in the tracker's calibrated frame R_cal,k = q_k o_k (the tracker's orientation times
// its calibration offset: X left, Y up, Z forward of the body at the calibration frame), metres,
// absolute (they do not scale with the body: devices have one size):
//   headset position  = head joint  + R_cal,head e      e   = (0, 0.08, 0.10)
//     (OpenXR's view pose is between the eyes, 8-12 cm above and in front of a mocap head joint)
//   controller grip   = wrist joint + R_cal,hand g      g_L = g_R = (0, -0.08, 0.03)
//     (at a relaxed standing pose the grip is ~8 cm below and 3 cm in front of the wrist)
//   pelvis tracker    = hips joint, moved vertically at calibration so that the standing hips are at
//                       the standard skeleton's height (pelvis_from_standing)
// What the pipelines feed their networks is the inverse, then scaled to the standard skeleton:
//   joint = s (device - R_cal,k d_k)                  (features/calibration.hpp)
// Before any calibration a tracker's orientation offset is a half turn about its own Y axis
// (OpenXR devices look along -Z, the body frame along +Z; recordings/tracker_synthesis.hpp
// to_openxr_convention is the forward direction of that).
//
// The same numbers are used by the Python training synthesis (weights_tool): keep them equal.
#pragma once
#include <array>
#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "sparsebody/trackers/types.hpp"

namespace sparsebody::features {

struct DeviceModel {
  Eigen::Vector3d eye{0.0, 0.08, 0.10};           // e: head joint -> headset (view pose)
  Eigen::Vector3d grip_left{0.0, -0.08, 0.03};    // g_L: left wrist -> left grip
  Eigen::Vector3d grip_right{0.0, -0.08, 0.03};   // g_R: right wrist -> right grip
  Eigen::Vector3d pelvis{0.0, 0.0, 0.0};          // hips joint -> pelvis tracker
  // The pelvis tracker's vertical offset measured at calibration instead (Calibration::
  // set_pelvis_height): at the standing frame it gives the standard standing hips height.
  bool pelvis_from_standing = true;
  // The pelvis tracker's calibrated orientation at the standing frame: the facing frame times
  // this, the standard performer's mean standing pelvis frame (a ~3 deg tilt; weights_tool/
  // devices.py PELVIS_STANDING, the chordal mean over the training clips' first frames).
  Eigen::Quaterniond pelvis_standing{0.999652291, -0.0217321878, -0.000325788787, -0.0149299376};  // w x y z

  // Trackers placed at the joints in the body convention (mocap synthesis without devices,
  // the training data): no offsets at all.
  static DeviceModel none() noexcept {
    DeviceModel m;
    m.eye = m.grip_left = m.grip_right = m.pelvis = Eigen::Vector3d::Zero();
    m.pelvis_from_standing = false;
    m.pelvis_standing = Eigen::Quaterniond::Identity();
    return m;
  }

  // d_k of tracker k (head, left hand, right hand, pelvis), calibrated frame, metres.
  const Eigen::Vector3d& offset(int k) const noexcept {
    switch (k) {
      case 0: return eye;
      case 1: return grip_left;
      case 2: return grip_right;
      default: return pelvis;
    }
  }
  std::array<Eigen::Vector3d, trackers::kTrackerCount> offsets() const noexcept { return {eye, grip_left, grip_right, pelvis}; }

  // The orientation offset of an uncalibrated tracker: half a turn about its Y axis, so that a
  // device looking along -Z gives a body frame looking along +Z.
  static Eigen::Quaterniond default_orientation_offset() noexcept {
    return Eigen::Quaterniond(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()));
  }
};

}  // namespace sparsebody::features
