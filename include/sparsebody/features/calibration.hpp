// Calibration (LoBSTr §4.2, shared by every pipeline): per-tracker orientation offsets o_k,
// positional device offsets d_k, a floor height and a height scale s to the standard skeleton.
//   orientation: o_k = q_k^-1 Yaw(headset forward) at the calibration frame, so that there every
//                calibrated tracker R_cal,k = q_k o_k has the body's facing frame (X left, Y up,
//                Z forward), the convention the networks were trained with
//                (recordings/tracker_synthesis.hpp);
//   position:    d_k in the calibrated frame, metres (features/device_model.hpp): the joint is at
//                p_k - R_cal,k d_k;
//   scale:       s = standing head-joint height of the standard skeleton / the user's, the user's
//                being the standing headset (eye) height above the floor minus e.y. (A pelvis-height
//                variant, ScaleFrom::Pelvis, uses the pelvis tracker when there is one.)
// apply() gives the network's joints: (s (p - floor y - R_cal d), R_cal). The output pose is
// divided by s to match the user's size.
//
// A default-constructed Calibration is the identity (no offsets, s = 1): for trackers that are the
// joints already in the body convention (mocap synthesis, the training data).
// Calibration::uncalibrated(devices) is what a pipeline runs with before it has calibrated a real
// headset session: half-turn orientation offsets (OpenXR devices look along -Z), the device
// offsets, s = 1 (the default body).
#pragma once
#include <array>
#include <cmath>
#include <utility>

#include "sparsebody/features/device_model.hpp"
#include "sparsebody/features/heading_frame.hpp"
#include "sparsebody/trackers/types.hpp"

namespace sparsebody::features {

enum class ScaleFrom { Head, Pelvis };

// Whether a new calibration whose scale is k times the old one is a refinement of the same body
// (within 5 %): the pipelines then carry their state over, rescaled, instead of restarting.
inline bool refines_size(double k) noexcept { return std::abs(k - 1.0) <= 0.05; }

struct Calibration {
  std::array<Eigen::Quaterniond, trackers::kTrackerCount> offset{
      Eigen::Quaterniond::Identity(), Eigen::Quaterniond::Identity(), Eigen::Quaterniond::Identity(),
      Eigen::Quaterniond::Identity()};
  std::array<Eigen::Vector3d, trackers::kTrackerCount> position_offset{
      Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};  // d_k
  double scale = 1.0;  // s: user -> standard skeleton
  double floor = 0.0;  // world y of the floor (the reference space's y = 0 unless estimated)
  // The user's standing hips-joint height in the standard skeleton's scale, from a pelvis tracker
  // at calibration (its height minus the device model's offset, times s); 0: not measured. The
  // pipelines size the output skeleton's legs by it (pose/body_proportions.hpp); the network keeps
  // seeing the standard height (set_pelvis_height).
  double hips_height = 0.0;

  // Before calibration: half-turn orientation offsets, the device offsets, the default body.
  static Calibration uncalibrated(const DeviceModel& d) noexcept {
    Calibration c;
    c.offset.fill(DeviceModel::default_orientation_offset());
    c.position_offset = d.offsets();
    return c;
  }

  // o_k = q_k^-1 Yaw(headset forward) for every tracker with valid[k]; the others keep theirs.
  // False (unchanged) when the headset orientation is not usable.
  // The pelvis tracker's target is the facing frame times pelvis_standing (the standard skeleton's
  // standing pelvis tilt, DeviceModel): a belt tracker's mounting is unknown, so it is calibrated to
  // what the network saw at the training clips' calibration frames.
  bool set_orientations(const std::array<Eigen::Quaterniond, trackers::kTrackerCount>& q,
                        const std::array<bool, trackers::kTrackerCount>& valid,
                        const Eigen::Quaterniond& pelvis_standing = Eigen::Quaterniond::Identity()) noexcept {
    if (!valid[0] || !q[0].coeffs().allFinite()) return false;
    const Eigen::Matrix3d yaw = facing(q[0]);
    if (!yaw.allFinite()) return false;
    for (int k = 0; k < trackers::kTrackerCount; ++k)
      if (valid[k] && q[k].coeffs().allFinite())
        offset[k] = Eigen::Quaterniond(q[k].normalized().toRotationMatrix().transpose() *
                                       (k == 3 ? Eigen::Matrix3d(yaw * pelvis_standing.toRotationMatrix()) : yaw));
    return true;
  }

  // The body's facing frame from a headset orientation (OpenXR: the headset looks along its -Z).
  static Eigen::Matrix3d facing(const Eigen::Quaterniond& head) noexcept {
    return yaw_frame(-(head.normalized() * Eigen::Vector3d::UnitZ()), Eigen::Matrix3d::Identity());
  }


  // From one frame of the user standing upright facing forward (a T-pose or any standing frame;
  // the head must be valid). Offsets o_k from the frame, d_k from `devices`, the floor at y = 0,
  // s from the head (or, ScaleFrom::Pelvis, from the pelvis tracker where valid and above 0.3 m).
  // Returns false (calibration unchanged) when the frame cannot be used.
  bool from_tpose(const trackers::TrackerFrame& f, double standard_hips_height, double standard_head_height,
                  const DeviceModel& devices = DeviceModel{}, ScaleFrom from = ScaleFrom::Head) noexcept {
    using trackers::to_eigen;
    if (!f.valid[0] || !to_eigen(f.pose[0].position).allFinite()) return false;
    std::array<Eigen::Quaterniond, trackers::kTrackerCount> q;
    for (int k = 0; k < trackers::kTrackerCount; ++k) q[k] = to_eigen(f.pose[k].orientation);
    Calibration c = uncalibrated(devices);
    if (!c.set_orientations(q, f.valid, devices.pelvis_standing)) return false;
    const double hp = f.pose[3].position.y, hh = f.pose[0].position.y - devices.eye.y();
    if (from == ScaleFrom::Pelvis && f.valid[3] && hp > 0.3) c.scale = standard_hips_height / hp;
    else if (hh > 0.5) c.scale = standard_head_height / hh;
    else return false;
    if (f.valid[3] && std::isfinite(hp)) c.set_pelvis_height(hp, standard_hips_height, devices);
    *this = c;
    return true;
  }

  // The controllers were found in the other hands (trackers/controller_swap.hpp) and their roles
  // exchanged: each orientation offset o_k was measured on a device, so it follows the device; the
  // positional offsets d_k belong to the hands (mirrored grips) and stay.
  void swap_controllers() noexcept { std::swap(offset[1], offset[2]); }

  // The pelvis tracker's offset from the calibration frame (scale and floor already set): along
  // the calibrated pelvis's up axis (vertical there), so that the joint it gives sits at the
  // standard skeleton's standing hips height. Where a belt tracker sits on a user, and how high a
  // body's hips are for its head height, differ; the network has only seen the standard standing
  // height (LoBSTr's p_ref,y input), and reads a lower one as a crouch (weights_tool/devices.py
  // does the same to the training data). Only with devices.pelvis_from_standing and a standard
  // height > 0; the horizontal offset stays the device model's.
  void set_pelvis_height(double pelvis_y, double standard_hips_height, const DeviceModel& devices) noexcept {
    if (!devices.pelvis_from_standing || !(standard_hips_height > 0) || !std::isfinite(pelvis_y) || !(scale > 0)) return;
    hips_height = (pelvis_y - floor - devices.pelvis.y()) * scale;
    position_offset[3] = devices.pelvis;
    position_offset[3].y() = pelvis_y - floor - standard_hips_height / scale;
  }

  // Calibrated joint pose of tracker k in the standard skeleton's scale.
  trackers::PoseD apply(int k, const trackers::PoseD& in) const noexcept {
    trackers::PoseD out;
    out.orientation = in.orientation * offset[k];
    out.position = in.position - out.orientation * position_offset[k];
    out.position.y() -= floor;
    out.position *= scale;
    return out;
  }
  void apply(const std::array<trackers::PoseD, trackers::kTrackerCount>& in,
             std::array<trackers::PoseD, trackers::kTrackerCount>& out) const noexcept {
    for (int k = 0; k < trackers::kTrackerCount; ++k) out[k] = apply(k, in[k]);
  }
};

}  // namespace sparsebody::features
