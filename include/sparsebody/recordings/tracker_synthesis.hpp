// Synthetic trackers from mocap (training data, demos, tests): headset at the head joint,
// controllers at the hand joints, pelvis tracker at the hips joint. Python twin:
// weights_tool/lobstr/skeleton.py Clip.trackers (keep equal; the parity test checks it).
//   pelvis orientation = W_hips(t) F_local, F_local = hips_tracker_frame (rest geometry: Y up to
//                        spine_base, X left, Z forward), rigid with the hips joint (pose/joint_map.hpp)
//   head/hand orientation = W_k(t) o_k,  o_k = W_k(t0)^T Yaw(F_hips(t0) at t0 = 0)
// i.e. at the first frame every tracker's axes are the body's facing frame, which is what
// calibration (features/calibration.hpp) makes of a user's trackers. Positions are in metres with
// the floor (estimated from the toes) at y = 0.
#pragma once
#include <algorithm>
#include <vector>

#include "sparsebody/recordings/bvh.hpp"
#include "sparsebody/features/heading_frame.hpp"
#include "sparsebody/pose/joint_map.hpp"
#include "sparsebody/trackers/types.hpp"

namespace sparsebody::recordings {
using trackers::TrackerFrame;
using trackers::to_eigen;
using trackers::to_xr;

// Metres per file unit guessed from the leg length (cm, m, inches, mm; else a 0.85 m leg).
inline double guess_units(const pose::Skeleton& s, const pose::JointMap& m) noexcept {
  const double leg = pose::leg_length(s, m);
  for (double u : {0.01, 1.0, 0.0254, 0.001})
    if (leg * u > 0.5 && leg * u < 1.2) return u;
  return 0.85 / leg;
}

struct SyntheticTrackers {
  std::vector<TrackerFrame> frames;  // one per BVH frame, time = f * frame_time
  double units = 1;                  // metres per file unit
  double floor = 0;                  // file floor height (metres) subtracted from y
  double leg = 0;                    // clip leg length (metres)
};

inline SyntheticTrackers synthesize_trackers(const BvhClip& clip, const pose::JointMap& m, double units) {
  using pose::Role;
  const pose::Skeleton& s = clip.skeleton;
  SyntheticTrackers out;
  out.units = units;
  out.leg = pose::leg_length(s, m) * units;
  pose::BodyPose tmp;
  tmp.resize(s.size());
  pose::Vec3Vector tr(static_cast<std::size_t>(s.size()));
  pose::WorldPose w;
  w.resize(s.size());
  const Eigen::Matrix3d F_local = pose::hips_tracker_frame(s, m);
  const int joints[3] = {m[Role::Head], m[Role::HandL], m[Role::HandR]};
  std::vector<double> toe_y;
  Eigen::Matrix3d o[3];
  out.frames.resize(static_cast<std::size_t>(clip.frames));
  for (int f = 0; f < clip.frames; ++f) {
    clip.world_pose(f, tmp, tr, w, units);
    const Eigen::Matrix3d Fh = w.rotation[m[Role::Hips]].toRotationMatrix() * F_local;
    if (f == 0) {
      const Eigen::Matrix3d yaw0 = features::yaw_frame(Fh.col(2), Eigen::Matrix3d::Identity());
      for (int k = 0; k < 3; ++k) o[k] = w.rotation[joints[k]].toRotationMatrix().transpose() * yaw0;
    }
    TrackerFrame& t = out.frames[f];
    t.time = f * clip.frame_time;
    for (int k = 0; k < 3; ++k) {
      t.pose[k].position = to_xr(w.position[joints[k]]);
      t.pose[k].orientation = to_xr(Eigen::Quaterniond(w.rotation[joints[k]].toRotationMatrix() * o[k]));
      t.valid[k] = true;
    }
    t.pose[3].position = to_xr(w.position[m[Role::Hips]]);
    t.pose[3].orientation = to_xr(Eigen::Quaterniond(Fh));
    t.valid[3] = true;
    toe_y.push_back(w.position[m[Role::ToeL]].y());
    toe_y.push_back(w.position[m[Role::ToeR]].y());
  }
  if (!toe_y.empty()) {  // floor: 2nd percentile of toe heights minus the standing toe height
    std::sort(toe_y.begin(), toe_y.end());
    const double pos = 0.02 * (toe_y.size() - 1);
    const std::size_t i = static_cast<std::size_t>(pos);
    const double v = toe_y[i] + (i + 1 < toe_y.size() ? (pos - i) * (toe_y[i + 1] - toe_y[i]) : 0.0);
    out.floor = v - 0.042 * out.leg / 0.80;
  }
  for (auto& t : out.frames)
    for (auto& p : t.pose) p.position.y = static_cast<float>(p.position.y - out.floor);
  return out;
}

// Synthetic trackers use the body convention (every tracker's Z axis forward at the first frame);
// OpenXR devices look along -Z. This turns each tracker half a turn about its own Y axis so that a
// recorded stream (CSV) looks like a headset session; T-pose calibration maps it back.
inline void to_openxr_convention(std::vector<TrackerFrame>& frames) noexcept {
  const Eigen::Quaterniond half(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()));
  for (auto& f : frames)
    for (auto& p : f.pose) p.orientation = to_xr(Eigen::Quaterniond(to_eigen(p.orientation) * half));
}

}  // namespace sparsebody::recordings
