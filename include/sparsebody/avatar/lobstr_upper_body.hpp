// LoBSTr's upper body (the network predicts the lower body only; Yang et al. 2021 drive the rest
// from the trackers by IK): the spine chain straight from its base towards the head tracker (twist
// from the body's left axis), the head from the headset's orientation, the clavicles outwards, and
// two-bone IK (pose::limb_to, aimed bones) from the shoulders to the hand trackers with the elbows
// down and back, the hands in the controllers' orientation. Works on any skeleton with the joint
// roles of pose/joint_map.hpp (3-joint arms without a clavicle included). No allocation.
#pragma once
#include <array>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "sparsebody/pose/body_pose.hpp"
#include "sparsebody/pose/ik.hpp"
#include "sparsebody/pose/joint_map.hpp"
#include "sparsebody/pose/skeleton.hpp"
#include "sparsebody/trackers/types.hpp"

namespace sparsebody::avatar {

class LoBSTrUpperBody {
 public:
  LoBSTrUpperBody() = default;

  // The spine chain (hips' spine child .. head), arms (upper, lower, hand, clavicle) and chest of s.
  LoBSTrUpperBody(const pose::Skeleton& s, const pose::JointMap& map) {
    const int head = map[pose::Role::Head];
    int j = head;
    spine_n_ = 0;
    while (j > 0 && spine_n_ < 8) { spine_rev_[spine_n_++] = j; j = s.parents[j]; }
    // spine_rev_ = head, neck, chest, ..., first spine joint (child of the hips)
    for (int side = 0; side < 2; ++side) {
      const int hand = map[side == 0 ? pose::Role::HandL : pose::Role::HandR];
      arm_[side][2] = hand;
      arm_[side][1] = s.parents[hand];
      arm_[side][0] = s.parents[arm_[side][1]];
      arm_[side][3] = s.parents[arm_[side][0]];  // clavicle (or the chest for 3-joint arms)
    }
    chest_ = s.parents[arm_[0][3]];
    if (arm_[0][3] == chest_ || chest_ < 0) chest_ = arm_[0][3];
    lateral_local_ = s.offsets[arm_[0][3]] - s.offsets[arm_[1][3]];
    if (lateral_local_.norm() < 1e-6) lateral_local_ = Eigen::Vector3d::UnitZ();
  }

  // The shoulder joint (the upper arm's root) of side 0 (left) or 1 (right).
  int shoulder(int side) const noexcept { return arm_[side][0]; }

  // cal: the calibrated trackers (head, left hand, right hand, pelvis: X left, Y up, Z forward).
  // pose: root position and hips rotation set; writes the upper body's local rotations. world:
  // forward kinematics of the spine and clavicles (the arms' is the caller's).
  void solve(const pose::Skeleton& s, const std::array<trackers::PoseD, trackers::kTrackerCount>& cal, pose::BodyPose& pose,
             pose::WorldPose& world) const noexcept {
    const Eigen::Vector3d left_body = cal[3].orientation.toRotationMatrix().col(0);
    const Eigen::Vector3d up_body = cal[3].orientation.toRotationMatrix().col(1);
    solve_spine(s, cal[0], left_body, up_body, pose);
    pose::forward_kinematics(s, pose, world);
    const Eigen::Vector3d fwd_body = cal[3].orientation.toRotationMatrix().col(2);
    for (int side = 0; side < 2; ++side) {  // clavicles outwards (independent of each other)
      const int clav = arm_[side][3];
      if (clav == chest_) continue;
      const double sgn = side == 0 ? 1.0 : -1.0;
      const Eigen::Quaterniond w = pose::aim(bone_local(s, clav), Eigen::Vector3d::UnitY(), sgn * left_body, fwd_body);
      pose.local[clav] = (world.rotation[s.parents[clav]].conjugate() * w).normalized();
    }
    pose::forward_kinematics(s, pose, world);
    for (int side = 0; side < 2; ++side) solve_arm(s, side, cal[1 + side], left_body, up_body, fwd_body, pose, world);
  }

 private:
  // Bone direction of joint j in its own frame (towards its first child; a leaf continues its parent's bone).
  static Eigen::Vector3d bone_local(const pose::Skeleton& s, int j) noexcept {
    const int c = s.first_child(j);
    const Eigen::Vector3d d = c >= 0 ? s.offsets[c] : s.offsets[j];
    return d.norm() > 1e-9 ? Eigen::Vector3d(d.normalized()) : Eigen::Vector3d::UnitX();
  }

  // Spine joints aimed from the chain's base at the headset, the head along the headset's axes
  // (world rotations parents first, written as locals).
  void solve_spine(const pose::Skeleton& s, const trackers::PoseD& head, const Eigen::Vector3d& left_body,
                   const Eigen::Vector3d& up_body, pose::BodyPose& pose) const noexcept {
    const Eigen::Matrix3d H = head.orientation.toRotationMatrix();
    const Eigen::Matrix3d Wh = pose.local[0].toRotationMatrix();
    const int base = spine_rev_[spine_n_ - 1];
    const Eigen::Vector3d base_pos = pose.root_position + Wh * s.offsets[base];
    Eigen::Vector3d dir = head.position - base_pos;
    if (dir.norm() < 1e-6) dir = up_body;
    dir.normalize();
    Eigen::Quaterniond parent_w(Wh);
    for (int i = spine_n_ - 1; i >= 0; --i) {
      const int j = spine_rev_[i];
      Eigen::Quaterniond w;
      if (i == 0) {  // head: its bone axis along the headset's up, lateral along its left
        w = pose::aim(bone_local(s, j), lateral_local_, H.col(1), H.col(0));
      } else {
        w = pose::aim(bone_local(s, j), lateral_local_, dir, left_body);
      }
      pose.local[j] = (parent_w.conjugate() * w).normalized();
      parent_w = w;
    }
  }

  // One arm: the hand joint on its controller, the elbow bent towards down-and-back (pole), the
  // bones aimed with the body's forward as twist, the hand in the controller's orientation.
  void solve_arm(const pose::Skeleton& s, int side, const trackers::PoseD& hand_tracker, const Eigen::Vector3d& left_body,
                 const Eigen::Vector3d& up_body, const Eigen::Vector3d& fwd_body, pose::BodyPose& pose,
                 const pose::WorldPose& w) const noexcept {
    const int clav = arm_[side][3], up = arm_[side][0], lo = arm_[side][1], hand = arm_[side][2];
    const double sgn = side == 0 ? 1.0 : -1.0;
    const Eigen::Vector3d pole = -up_body - 0.5 * fwd_body + 0.2 * sgn * left_body;
    const auto ik = pose::limb_to(w.position[up], w.position[lo], w.position[hand], w.rotation[up], w.rotation[lo],
                                  hand_tracker.position, pole,
                                  pose::LimbRotation::aimed(bone_local(s, up), bone_local(s, lo), Eigen::Vector3d::UnitY(), fwd_body));
    const Eigen::Matrix3d Ht = hand_tracker.orientation.toRotationMatrix();
    const Eigen::Quaterniond Wd = pose::aim(bone_local(s, hand), Eigen::Vector3d::UnitY(), sgn * Ht.col(0), Ht.col(1));
    const int arm[3] = {up, lo, hand};
    pose::set_limb_locals(pose, arm, &w.rotation[clav], ik.upper, ik.lower, Wd, true);
  }

  int spine_rev_[8] = {}, spine_n_ = 0;
  int arm_[2][4] = {};  // upper arm, lower arm, hand, clavicle (or chest) per side
  int chest_ = 0;
  Eigen::Vector3d lateral_local_ = Eigen::Vector3d::UnitZ();
};

}  // namespace sparsebody::avatar
