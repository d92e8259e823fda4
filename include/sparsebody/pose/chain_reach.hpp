// Bend a chain of joints so that its end joint reaches a target: the spine (its base .. the neck)
// putting the head joint where the headset says it is. Cyclic coordinate descent (CCD, Wang & Chen
// 1991): pass after pass, each chain joint from the base up turns by the shortest rotation that
// points its (joint -> end) vector at the target, at most `max_angle` per joint and pass, so a
// correction is spread over the spine instead of folding the neck. The end joint keeps its world
// rotation (the head still looks where it looked). No allocation: the chain is at most kMax joints.
#pragma once
#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Geometry>

#include "sparsebody/pose/body_pose.hpp"
#include "sparsebody/pose/ik.hpp"
#include "sparsebody/pose/skeleton.hpp"

namespace sparsebody::pose {

struct ChainReachConfig {
  int passes = 3;
  double max_angle = 0.17;  // rad per joint and pass (~10 deg): at most ~30 deg per joint in all
  double tolerance = 1e-3;  // m: closer than this, stop
};

class ChainReach {
 public:
  static constexpr int kMax = 8;

  ChainReach() = default;
  // The chain of `end` (e.g. the head): its ancestors below `end`, up to `levels` of them, stopping
  // before the root (the hips stay where the legs put them). Empty when end is not a joint.
  ChainReach(const Skeleton& s, int end, int levels = 4) noexcept : end_(end) {
    if (end < 0 || end >= s.size()) return;
    for (int j = s.parents[end]; j >= 0 && s.parents[j] >= 0 && n_ < std::min(levels, kMax); j = s.parents[j]) chain_[n_++] = j;
    // chain_ = neck, chest, ..., lowest spine joint: solved from the last (the base) up
  }
  bool empty() const noexcept { return n_ == 0; }
  int size() const noexcept { return n_; }

  // w must be the forward kinematics of pose. Changes pose.local of the chain and the end joint;
  // w holds the chain and end joint's new world poses but is stale for other branches (the
  // clavicles and arms): run forward kinematics after. Returns the end joint's remaining distance.
  double solve(const Skeleton& s, BodyPose& pose, WorldPose& w, const Eigen::Vector3d& target,
               const ChainReachConfig& cfg = {}) const noexcept {
    if (n_ == 0 || !target.allFinite()) return std::numeric_limits<double>::quiet_NaN();
    const Eigen::Quaterniond end_world = w.rotation[end_];
    for (int pass = 0; pass < cfg.passes; ++pass) {
      if ((w.position[end_] - target).norm() < cfg.tolerance) break;
      for (int i = n_ - 1; i >= 0; --i) {
        const int j = chain_[i];
        const Eigen::Vector3d pj = w.position[j];
        const Eigen::Vector3d to_end = w.position[end_] - pj, to_target = target - pj;
        if (to_end.norm() < 1e-6 || to_target.norm() < 1e-6) continue;
        Eigen::AngleAxisd r(swing(to_end, to_target));
        if (!std::isfinite(r.angle())) continue;
        if (r.angle() > cfg.max_angle) r.angle() = cfg.max_angle;
        const Eigen::Quaterniond q(r);
        // turn joint j and what hangs from it on the chain (the joints above it, and the end)
        for (int k = i; k >= 0; --k) {
          const int c = chain_[k];
          if (k != i) w.position[c] = pj + q * (w.position[c] - pj);
          w.rotation[c] = (q * w.rotation[c]).normalized();
        }
        w.position[end_] = pj + q * (w.position[end_] - pj);
      }
    }
    // back to locals, base first; the end joint keeps its world rotation
    for (int i = n_ - 1; i >= 0; --i) {
      const int j = chain_[i];
      pose.local[j] = (w.rotation[s.parents[j]].conjugate() * w.rotation[j]).normalized();
    }
    w.rotation[end_] = end_world;
    pose.local[end_] = (w.rotation[chain_[0]].conjugate() * end_world).normalized();
    return (w.position[end_] - target).norm();
  }

 private:
  int chain_[kMax] = {};
  int n_ = 0;
  int end_ = -1;
};

}  // namespace sparsebody::pose
