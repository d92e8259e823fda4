// A full-body pose on a skeleton: root position (metres, world) + local joint rotations, and
// forward kinematics to world transforms. Storage is sized once (resize) and reused per frame.
#pragma once
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/StdVector>

#include "sparsebody/pose/skeleton.hpp"

namespace sparsebody::pose {

using QuatVector = std::vector<Eigen::Quaterniond, Eigen::aligned_allocator<Eigen::Quaterniond>>;
using Vec3Vector = std::vector<Eigen::Vector3d>;

struct BodyPose {
  Eigen::Vector3d root_position = Eigen::Vector3d::Zero();
  QuatVector local;  // one per joint; local[0] is the root's world rotation

  void resize(int joints) { local.assign(static_cast<std::size_t>(joints), Eigen::Quaterniond::Identity()); }
};

// World transforms of a pose (positions p_j, rotations W_j): W_j = W_parent L_j,
// p_j = p_parent + W_parent offset_j (the root at root_position). `scale` multiplies the offsets.
struct WorldPose {
  Vec3Vector position;
  QuatVector rotation;
  void resize(int joints) {
    position.assign(static_cast<std::size_t>(joints), Eigen::Vector3d::Zero());
    rotation.assign(static_cast<std::size_t>(joints), Eigen::Quaterniond::Identity());
  }
};

inline void forward_kinematics(const Skeleton& s, const BodyPose& p, WorldPose& w, double scale = 1.0) noexcept {
  for (int j = 0; j < s.size(); ++j) {
    const int par = s.parents[j];
    if (par < 0) {
      w.rotation[j] = p.local[j];
      w.position[j] = p.root_position;
    } else {
      w.rotation[j] = w.rotation[par] * p.local[j];
      w.position[j] = w.position[par] + w.rotation[par] * (scale * s.offsets[j]);
    }
  }
}

}  // namespace sparsebody::pose
