// Synthetic headset sessions in OpenXR conventions (devices look along -Z, floor y = 0) made of
// phases: standing still (a 3 mm sway), walking (1 m/s, a 2 cm bob, swinging controllers),
// sitting (standing still, lower). For the automatic-calibration tests.
#pragma once
#include <cmath>
#include <vector>

#include <Eigen/Geometry>

#include "sparsebody/trackers/types.hpp"

namespace sparsebody_test {

struct Phase {
  enum Kind { Stand, Walk } kind = Stand;
  double seconds = 1.0;
  double eye = 1.62;  // headset height (m)
  double belt = 0.6;  // pelvis tracker height / headset height (0.6: about the standard proportions' hips)
};

// Frames at `rate` Hz; the user faces -Z (identity headset orientation) turned by `yaw` about +Y.
inline std::vector<sparsebody::trackers::TrackerFrame> session(const std::vector<Phase>& phases, double rate = 30.0,
                                                               double yaw = 0.3, bool pelvis = true) {
  using namespace sparsebody;
  std::vector<trackers::TrackerFrame> out;
  const Eigen::Quaterniond q(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()));
  const Eigen::Vector3d fwd = q * Eigen::Vector3d(0, 0, -1), left = q * Eigen::Vector3d(-1, 0, 0);
  Eigen::Vector3d base(0.5, 0, -0.3);
  long i = 0;
  for (const Phase& ph : phases) {
    const long n = std::lround(ph.seconds * rate);
    for (long j = 0; j < n; ++j, ++i) {
      const double t = i / rate, tl = j / rate;
      trackers::TrackerFrame f;
      f.time = t;
      Eigen::Vector3d head = base + Eigen::Vector3d(0, ph.eye, 0);
      double swing = 0;
      if (ph.kind == Phase::Walk) {
        head += fwd * tl + Eigen::Vector3d(0, 0.02 * std::sin(2 * M_PI * 2 * tl), 0);
        swing = 0.2 * std::sin(2 * M_PI * 1 * tl);
      } else {
        head += left * 0.003 * std::sin(2 * M_PI * 0.3 * tl);
      }
      const double arm = 0.55 * ph.eye / 1.62;
      const Eigen::Vector3d hand[2] = {head + left * 0.22 - Eigen::Vector3d(0, arm, 0) + fwd * (0.1 + swing),
                                       head - left * 0.22 - Eigen::Vector3d(0, arm, 0) + fwd * (0.1 - swing)};
      f.pose[0] = {trackers::to_xr(q), trackers::to_xr(head)};
      f.pose[1] = {trackers::to_xr(q), trackers::to_xr(hand[0])};
      f.pose[2] = {trackers::to_xr(q), trackers::to_xr(hand[1])};
      f.pose[3] = {trackers::to_xr(q), trackers::to_xr(Eigen::Vector3d(head.x(), ph.belt * ph.eye, head.z()))};
      f.valid = {true, true, true, pelvis};
      out.push_back(f);
    }
    if (ph.kind == Phase::Walk) base += fwd * ph.seconds;
  }
  return out;
}

// Appends `seconds` of the user standing where the last frame stands with both controllers held out
// in front, `reach` m ahead of the headset and 0.2 m below it, 0.2 m to each side (arms stretched:
// for the arm-reach tests, pose/arm_reach.hpp).
inline void reach_out(std::vector<sparsebody::trackers::TrackerFrame>& frames, double seconds, double reach, double rate = 30.0) {
  using namespace sparsebody;
  const trackers::TrackerFrame last = frames.back();
  const Eigen::Quaterniond q = trackers::to_eigen(last.pose[0].orientation);
  const Eigen::Vector3d fwd = q * Eigen::Vector3d(0, 0, -1), left = q * Eigen::Vector3d(-1, 0, 0);
  const Eigen::Vector3d head = trackers::to_eigen(last.pose[0].position);
  const long n = std::lround(seconds * rate);
  for (long j = 1; j <= n; ++j) {
    trackers::TrackerFrame f = last;
    f.time = last.time + j / rate;
    f.pose[1].position = trackers::to_xr(Eigen::Vector3d(head + fwd * reach - Eigen::Vector3d(0, 0.2, 0) + left * 0.2));
    f.pose[2].position = trackers::to_xr(Eigen::Vector3d(head + fwd * reach - Eigen::Vector3d(0, 0.2, 0) - left * 0.2));
    frames.push_back(f);
  }
}

}  // namespace sparsebody_test
