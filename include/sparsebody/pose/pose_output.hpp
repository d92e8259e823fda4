// A pipeline's output pose with the last-good guard: the pipeline writes its frame into pose() and
// world(), then commit() hands it out when every number is finite, and otherwise puts the last
// finite pose back (so a caller never sees a NaN, only a held pose). has_output(): a frame was
// committed since the last reset. Storage is sized once; copies reuse it (no allocation per frame).
#pragma once
#include "sparsebody/pose/body_pose.hpp"

namespace sparsebody::pose {

// Root position, local rotations and world positions all finite (world rotations follow from the
// locals by FK).
inline bool all_finite(const BodyPose& p, const WorldPose& w) noexcept {
  bool ok = p.root_position.allFinite();
  for (std::size_t j = 0; j < p.local.size(); ++j) ok &= p.local[j].coeffs().allFinite() && w.position[j].allFinite();
  return ok;
}

class PoseOutput {
 public:
  void resize(int joints) {
    pose_.resize(joints);
    world_.resize(joints);
    last_pose_ = pose_;
    last_world_ = world_;
  }

  // The frame being built (the pipeline writes here) and, after commit(), the output.
  BodyPose& pose() noexcept { return pose_; }
  WorldPose& world() noexcept { return world_; }
  const BodyPose& pose() const noexcept { return pose_; }
  const WorldPose& world() const noexcept { return world_; }
  bool has_output() const noexcept { return valid_; }

  // Accepts the frame (true) when finite; else restores the last accepted one (false) and leaves
  // has_output() as it was. The caller decides what a rejected frame restarts.
  bool commit() noexcept {
    if (!all_finite(pose_, world_)) {
      pose_ = last_pose_;
      world_ = last_world_;
      return false;
    }
    last_pose_ = pose_;
    last_world_ = world_;
    valid_ = true;
    return true;
  }

  // No output until the next commit (e.g. no usable input this frame); the poses are kept.
  void invalidate() noexcept { valid_ = false; }
  // Back to the state resize() left: no output, identity rotations, zero positions (a pipeline
  // that reads its previous frame, e.g. IK seeded from the last arm pose, then restarts exactly as
  // a new instance would: tests/determinism). assign() on the sized vectors does not allocate.
  void reset() noexcept {
    valid_ = false;
    for (BodyPose* p : {&pose_, &last_pose_}) {
      p->root_position.setZero();
      p->local.assign(p->local.size(), Eigen::Quaterniond::Identity());
    }
    for (WorldPose* w : {&world_, &last_world_}) {
      w->position.assign(w->position.size(), Eigen::Vector3d::Zero());
      w->rotation.assign(w->rotation.size(), Eigen::Quaterniond::Identity());
    }
  }

 private:
  BodyPose pose_, last_pose_;
  WorldPose world_, last_world_;
  bool valid_ = false;
};

}  // namespace sparsebody::pose
