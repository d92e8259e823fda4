// A BVH clip's up axis, read from its motion. BVH is Y-up by convention, but clips converted from
// Z-up data (AMASS / SMPL exports, Blender or 3ds Max scenes written without converting) have a
// Z-up world, and a Y-up pipeline reads them as a body lying on its back: every tracker wrong and
// no error (the CMU clip 01_01 turned Z-up: LoBSTr MPJPE 11.0 -> 22.4 cm, toes 20 -> 46 cm).
// Rule: on up to 240 frames spread over the clip, the signed world axis nearest to the hips -> head
// direction; when one axis other than +Y is that axis on at least `min_share` of them (a VR user is
// upright most of the time; a clip that lies down throughout is left alone), the clip is turned so
// that this axis becomes +Y (BvhClip::world_turn, the shortest rotation: +Z -> +Y is -90 deg about X).
// Python twin: weights_tool/lobstr/skeleton.py up_axis_turn (keep equal).
#pragma once
#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

#include "sparsebody/pose/joint_map.hpp"
#include "sparsebody/recordings/bvh.hpp"

namespace sparsebody::recordings {

struct UpAxis {
  int axis = 1;        // 0 x, 1 y, 2 z: the file's up axis
  int sign = 1;        // +1 / -1
  double share = 0;    // of the frames looked at, the share with hips -> head nearest that axis
  bool turned = false; // the clip was turned to +Y
  char name() const noexcept { return "XYZ"[axis]; }
};

// Finds the clip's up axis and, when it is not +Y, sets clip.world_turn to turn it to +Y.
inline UpAxis make_y_up(BvhClip& clip, const pose::JointMap& m, double min_share = 0.7) {
  UpAxis out;
  clip.world_turn = Eigen::Quaterniond::Identity();
  const int n = std::min(clip.frames, 240);
  if (n <= 0) return out;
  const int head = m[pose::Role::Head], hips = m[pose::Role::Hips];
  pose::BodyPose tmp;
  tmp.resize(clip.skeleton.size());
  pose::Vec3Vector tr(static_cast<std::size_t>(clip.skeleton.size()));
  pose::WorldPose w;
  w.resize(clip.skeleton.size());
  int votes[6] = {};  // +x -x +y -y +z -z
  int counted = 0;
  for (int i = 0; i < n; ++i) {
    const int f = n > 1 ? static_cast<int>(static_cast<long long>(i) * (clip.frames - 1) / (n - 1)) : 0;
    clip.world_pose(f, tmp, tr, w);
    const Eigen::Vector3d d = w.position[head] - w.position[hips];
    if (!(d.squaredNorm() > 0) || !d.allFinite()) continue;
    int a = 0;
    d.cwiseAbs().maxCoeff(&a);
    ++votes[2 * a + (d(a) < 0 ? 1 : 0)];
    ++counted;
  }
  if (counted == 0) return out;
  const int best = static_cast<int>(std::max_element(votes, votes + 6) - votes);
  out.axis = best / 2;
  out.sign = best % 2 ? -1 : 1;
  out.share = static_cast<double>(votes[best]) / counted;
  if (best == 2 || out.share < min_share) {  // +Y, or no clear other axis: as the file says
    out.axis = 1, out.sign = 1, out.share = static_cast<double>(votes[2]) / counted;
    return out;
  }
  Eigen::Vector3d up = Eigen::Vector3d::Zero();
  up(out.axis) = out.sign;
  clip.world_turn = best == 3 ? Eigen::Quaterniond(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()))  // upside down
                              : Eigen::Quaterniond::FromTwoVectors(up, Eigen::Vector3d::UnitY());
  out.turned = true;
  return out;
}

}  // namespace sparsebody::recordings
