// Synthetic trackers from mocap (training data, demos, tests): headset at the head joint,
// controllers at the hand joints, pelvis tracker at the hips joint (where the standard skeleton has
// it: pose::standard_hips_point, the rig's own root on every training clip; another rig's root,
// CMU's at the lower back, would put the avatar's hips ~10 cm too high and back). Python twin:
// weights_tool/lobstr/skeleton.py Clip.trackers (keep equal; the parity test checks it).
//   pelvis orientation = W_hips(t) F_local, F_local = hips_tracker_frame (rest geometry: Y up to
//                        spine_base, X left, Z forward), rigid with the hips joint (pose/joint_map.hpp)
//   head/hand orientation = W_k(t) o_k,  o_k = W_k(t0)^T Yaw(F_hips(t0) at t0 = 0)
// i.e. at the first frame every tracker's axes are the body's facing frame, which is what
// calibration (features/calibration.hpp) makes of a user's trackers. Positions are in metres with
// the floor (estimated from the toes) at y = 0.
//
// Device-realistic synthesis (synthesize_device_trackers, DeviceSynthesis): what a headset session
// of the same motion would record. The device model (features/device_model.hpp) is applied in the
// trackers' body-convention frame above (the calibrated frame of a calibration at frame 0):
// headset = head + R e, grips = wrists + R g, then the OpenXR orientation convention (half a turn
// about Y); optionally a per-session random perturbation (seeded), output at a device rate
// (interpolating the clip), timing jitter and short tracking losses. No T-pose, no hint of the
// calibration: a stream to calibrate automatically like a real session. Floor y = 0.
#pragma once
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "sparsebody/recordings/bvh.hpp"
#include "sparsebody/features/device_model.hpp"
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
  const Eigen::Vector3d hips_point = pose::standard_hips_point(s, m) * units;  // hips-local, metres
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
    t.pose[3].position = to_xr(Eigen::Vector3d(w.position[m[Role::Hips]] + w.rotation[m[Role::Hips]] * hips_point));
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

// Options of synthesize_device_trackers. Defaults: the device model as given, 72 Hz, no
// perturbation, no jitter, no losses, a pelvis tracker (drop it with pelvis = false).
struct DeviceSynthesis {
  features::DeviceModel devices{};
  double rate = 72.0;          // Hz of the output (the clip is interpolated); <= 0: the clip's frames
  bool pelvis = true;          // a pelvis tracker at the hips (no offset)
  // Per-session perturbation, drawn once from `seed` when perturb: eye offset +-2 cm per axis, grip
  // offset length 5-12 cm with its direction turned up to 30 deg, grip rotation up to 30 deg,
  // headset rotation up to 8 deg (how differently people wear and hold the devices).
  bool perturb = false;
  unsigned seed = 1;
  double timing_jitter = 0.0;  // s: each time stamp moves by up to this (uniform), e.g. 0.002
  double losses_per_second = 0.0;  // per tracker: short losses of 1-6 frames marked invalid
};

namespace detail {
inline Eigen::Quaterniond random_rotation(std::mt19937& rng, double max_angle) {
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.0, max_angle);
  Eigen::Vector3d axis(n(rng), n(rng), n(rng));
  if (!(axis.norm() > 1e-9)) axis = Eigen::Vector3d::UnitY();
  return Eigen::Quaterniond(Eigen::AngleAxisd(u(rng), axis.normalized()));
}
}  // namespace detail

// The device stream of a clip (OpenXR conventions, floor y = 0). frames hold the device poses at
// opt.rate; units / floor / leg as synthesize_trackers.
inline SyntheticTrackers synthesize_device_trackers(const BvhClip& clip, const pose::JointMap& m, double units,
                                                    const DeviceSynthesis& opt = {}) {
  SyntheticTrackers joints = synthesize_trackers(clip, m, units);
  features::DeviceModel d = opt.devices;
  std::array<Eigen::Quaterniond, trackers::kTrackerCount> mount;  // the device's rotation on the body frame
  mount.fill(Eigen::Quaterniond::Identity());
  std::mt19937 rng(opt.seed);
  if (opt.perturb) {
    std::uniform_real_distribution<double> cm(-0.02, 0.02), len(0.05, 0.12);
    d.eye += Eigen::Vector3d(cm(rng), cm(rng), cm(rng));
    for (Eigen::Vector3d* g : {&d.grip_left, &d.grip_right})
      if (g->norm() > 1e-9) *g = detail::random_rotation(rng, 30 * M_PI / 180) * (g->normalized() * len(rng));
    mount[0] = detail::random_rotation(rng, 8 * M_PI / 180);
    mount[1] = detail::random_rotation(rng, 30 * M_PI / 180);
    mount[2] = detail::random_rotation(rng, 30 * M_PI / 180);
  }
  const Eigen::Quaterniond half = features::DeviceModel::default_orientation_offset();
  // device poses per clip frame: p_dev = p_joint + R d_k, q_dev = R mount_k half (R: body-convention frame)
  std::vector<TrackerFrame> dev = joints.frames;
  for (auto& f : dev)
    for (int k = 0; k < trackers::kTrackerCount; ++k) {
      const Eigen::Quaterniond R = to_eigen(f.pose[k].orientation).normalized();
      f.pose[k].position = to_xr(Eigen::Vector3d(to_eigen(f.pose[k].position) + R * d.offset(k)));
      f.pose[k].orientation = to_xr(Eigen::Quaterniond(R * mount[k] * half).normalized());
      if (k == 3) f.valid[k] = opt.pelvis;
    }
  SyntheticTrackers out = joints;
  if (!(opt.rate > 0) || dev.size() < 2) {
    out.frames = std::move(dev);
  } else {
    const double dt = clip.frame_time, end = (dev.size() - 1) * dt;
    std::uniform_real_distribution<double> jit(-opt.timing_jitter, opt.timing_jitter);
    out.frames.clear();
    for (long i = 0;; ++i) {
      double t = i / opt.rate;
      if (opt.timing_jitter > 0) t = std::max(0.0, t + jit(rng));
      if (t > end) break;
      const double x = t / dt;
      const std::size_t a = std::min(static_cast<std::size_t>(x), dev.size() - 2);
      const double w = std::clamp(x - a, 0.0, 1.0);
      TrackerFrame f;
      f.time = t;
      for (int k = 0; k < trackers::kTrackerCount; ++k) {
        const auto &p0 = dev[a].pose[k], &p1 = dev[a + 1].pose[k];
        f.pose[k].position = to_xr(Eigen::Vector3d((1 - w) * to_eigen(p0.position) + w * to_eigen(p1.position)));
        f.pose[k].orientation = to_xr(to_eigen(p0.orientation).normalized().slerp(w, to_eigen(p1.orientation).normalized()));
        f.valid[k] = dev[a].valid[k];
      }
      out.frames.push_back(f);
    }
  }
  if (opt.losses_per_second > 0) {  // short losses: 1-6 frames of one tracker
    const double rate = opt.rate > 0 ? opt.rate : 1.0 / clip.frame_time;
    std::bernoulli_distribution start(std::min(1.0, opt.losses_per_second / rate));
    std::uniform_int_distribution<int> length(1, 6);
    for (int k = 0; k < trackers::kTrackerCount; ++k)
      for (std::size_t i = 0; i < out.frames.size(); ++i)
        if (out.frames[i].valid[k] && start(rng))
          for (int n = length(rng); n > 0 && i < out.frames.size(); --n, ++i) out.frames[i].valid[k] = false;
  }
  return out;
}

}  // namespace sparsebody::recordings
