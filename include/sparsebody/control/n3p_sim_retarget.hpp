// Pose <-> simulation model for the Neural3Points physics mode: the standard skeleton's joint
// rotations (pose::BodyPose, the predictor's output) become the avatar model's configuration q
// (character/avatar.hpp: same joint names and tree; reference pose a T-pose facing +Z with every
// joint frame aligned with the world) and back. The paper retargets "by copying the rotations of
// the corresponding joints" (§7); here the capture skeleton's joint frames are not the avatar's (its
// bones run along local X), so each joint j gets a constant alignment A_j and
//
//   world:  W^a_j = W^s_j A_j          local:  L^a_j = A_parent^-1 L^s_j A_j   (root: L^s A_root)
//
// A_j is fixed by the predictor's default standing pose N (meta.initial_state, facing +Z):
// A_j = (W^N_j)^-1 U_j, where U_j is the avatar's world rotation in that pose: the shortest
// rotation taking the avatar's bone direction (towards the chain child: Hips->Spine,
// Chest->Neck, UpperLeg->LowerLeg, ...) to the skeleton's bone direction in N; a leaf (Head,
// Hand, Toes) takes its parent's U. So the standing pose maps to the avatar standing with the
// same bone directions, and twist is measured from the same facing direction.
//   revolute joint : the twist angle of L^a_j about the hinge axis, 2 atan2(a . vec(L^a_j), w(L^a_j))
//                    (the swing part off the axis cannot be represented and is dropped)
//   free root      : the hip-joint centre (midpoint of the two UpperLeg joints) of the skeleton is
//                    put on the avatar's (its Hips origin), lifted by dy: the avatar's reference
//                    pose (straight legs, soles on the floor) corresponds to the skeleton standing
//                    straight at meta.standing_hips_height (the de Leva legs differ in length). Horizontal positions are kept: the character walks where the user
//                    walks. Trackers given to the simulation get the same lift (to_sim_point).
// Velocities: finite differences of two configurations in the model's velocity layout (spherical:
// log(q0^-1 q1) / dt in the child frame; free root: body-frame angular and linear velocity).
// Per call: no allocation.
#pragma once
#include <array>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "sparsebody/core/error.hpp"
#include "sparsebody/dynamics/kinematics.hpp"
#include "sparsebody/features/n3p_state.hpp"
#include "sparsebody/pose/body_pose.hpp"
#include "sparsebody/pose/rotation6d.hpp"
#include "sparsebody/pose/skeleton.hpp"

namespace sparsebody::control {

template <class S, int MB, int MD>
class N3PSimRetarget {
 public:
  using ModelT = dynamics::Model<S, MB, MD>;
  using VecQ = typename ModelT::VecQ;
  using VecV = typename ModelT::VecV;

  N3PSimRetarget() = default;
  // Every skeleton joint must be a body of the model with the same name and parent; the root must
  // be the model's free joint. `neutral`: world rotations of the skeleton's joints in the standing
  // pose, facing +Z (see neutral_rotations()); `neutral_hips_height`: the skeleton root's height
  // in it (sets the joint alignment); `standing_hips_height`: the skeleton's root height standing
  // straight (N3PMeta::standing_hips_height; sets the lift). Throws LoadError.
  N3PSimRetarget(const ModelT& m, const pose::Skeleton& s, const std::vector<Eigen::Matrix3d>& neutral,
                 double standing_hips_height) {
    if (s.size() != m.nb || m.nb > MB || static_cast<int>(neutral.size()) != s.size())
      throw LoadError("n3p_sim_retarget", "skeleton and model differ in joint count");
    for (int j = 0; j < s.size(); ++j) {
      body_[j] = m.find(s.names[j]);
      if (body_[j] < 0) throw LoadError("n3p_sim_retarget", "model lacks body " + s.names[j]);
      joint_[body_[j]] = j;
    }
    for (int j = 1; j < s.size(); ++j)
      if (m.bodies[body_[j]].parent != body_[s.parents[j]]) throw LoadError("n3p_sim_retarget", "tree differs at " + s.names[j]);
    if (body_[0] != m.root_body() || s.parents[0] >= 0)
      throw LoadError("n3p_sim_retarget", "the skeleton root must map to the model's free joint");
    n_ = s.size();
    // U_j: the avatar's world rotation in the standing pose (bone directions of N).
    std::vector<Eigen::Quaterniond> U(static_cast<std::size_t>(n_), Eigen::Quaterniond::Identity());
    for (int j = 0; j < n_; ++j) {
      const int c = s.first_child(j);
      if (c < 0) {
        U[j] = U[s.parents[j]];
        continue;
      }
      const Eigen::Vector3d avatar_bone = m.bodies[body_[c]].pos.template cast<double>();
      const Eigen::Vector3d skel_bone = neutral[j] * s.offsets[c];
      U[j] = Eigen::Quaterniond::FromTwoVectors(avatar_bone, skel_bone);
    }
    for (int j = 0; j < n_; ++j) {
      A_[j] = (Eigen::Quaterniond(neutral[j]).conjugate() * U[j]).normalized();
      Ainv_[j] = A_[j].conjugate();
    }
    // Hip-joint centre in the skeleton's root frame, and the lift.
    const int ul = s.find("UpperLeg_L"), ur = s.find("UpperLeg_R");
    if (ul < 0 || ur < 0 || s.parents[ul] != 0 || s.parents[ur] != 0)
      throw LoadError("n3p_sim_retarget", "the skeleton's UpperLeg_L/R must be children of the root");
    hip_centre_ = 0.5 * (s.offsets[ul] + s.offsets[ur]);
    // dy: the avatar's reference pose (identity joints: straight legs, soles on the floor) is the
    // skeleton standing straight with its root at `standing_hips_height`; their hip-joint centres
    // coincide: L^s_root = A_root^-1 there.
    dy_ = double(m.bodies[body_[0]].pos.y()) - (standing_hips_height + (Ainv_[0] * hip_centre_).y());
  }

  // World rotations of the predictor's default standing state (meta.initial_state g_lo^0, g_up^0 in
  // h^0, i.e. facing +Z), the `neutral` argument above.
  template <class Meta>
  static std::vector<Eigen::Matrix3d> neutral_rotations(const Meta& meta) {
    namespace n3p = features::n3p;
    std::vector<Eigen::Matrix3d> R(static_cast<std::size_t>(meta.skeleton.size()), Eigen::Matrix3d::Identity());
    for (int i = 0; i < n3p::kLowerJoints; ++i) R[meta.lower[i]] = pose::from6d(meta.glo0.data() + n3p::LowerBlock::rot(i));
    for (int i = 0; i < n3p::kUpperJoints; ++i) R[meta.upper[i]] = pose::from6d(meta.gup0.data() + n3p::UpperBlock::rot(i));
    return R;
  }
  template <class Meta>
  static N3PSimRetarget from_meta(const ModelT& m, const Meta& meta) {
    return N3PSimRetarget(m, meta.skeleton, neutral_rotations(meta), meta.standing_hips_height);
  }

  int joints() const noexcept { return n_; }
  int body_of(int joint) const noexcept { return body_[joint]; }
  int joint_of(int body) const noexcept { return joint_[body]; }
  double lift() const noexcept { return dy_; }  // dy
  const Eigen::Quaterniond& alignment(int joint) const noexcept { return A_[joint]; }  // A_j
  Eigen::Vector3d to_sim_point(const Eigen::Vector3d& p) const noexcept { return p + Eigen::Vector3d(0, dy_, 0); }
  Eigen::Vector3d from_sim_point(const Eigen::Vector3d& p) const noexcept { return p - Eigen::Vector3d(0, dy_, 0); }
  // Skeleton joint j's world state in a simulated state d (world kinematics with velocities):
  // position (back out of the simulation's lift), linear velocity of the body origin, and the
  // skeleton joint's rotation W^s = W^a A^-1. The policies' x_t (control/n3p_control_predictor.hpp,
  // control/n3p_target_correction.hpp).
  void joint_state(const dynamics::Data<S, MB, MD>& d, int j, Eigen::Vector3d& p, Eigen::Vector3d& v, Eigen::Matrix3d& R) const noexcept {
    const int b = body_[j];
    p = from_sim_point(d.p[b].template cast<double>());
    v = dynamics::point_velocity(d, b, dynamics::Vec3<S>::Zero().eval()).template cast<double>();
    R = d.R[b].template cast<double>() * A_[j].conjugate().toRotationMatrix();
  }

  // BodyPose -> q (q must be sized nq).
  void to_q(const ModelT& m, const pose::BodyPose& p, VecQ& q) const noexcept {
    for (int j = 0; j < n_; ++j) {
      const int i = body_[j];
      const dynamics::Body<S>& b = m.bodies[i];
      const int par = joint_parent(m, j);
      const Eigen::Quaterniond L = ((par < 0 ? p.local[j] : Ainv_[par] * p.local[j]) * A_[j]).normalized();
      const int k = b.q_index;
      switch (b.joint) {
        case dynamics::JointType::Free: {
          const Eigen::Vector3d r = to_sim_point(p.root_position + p.local[j] * hip_centre_);
          for (int a = 0; a < 3; ++a) q(k + a) = S(r[a]);
          write_quat(q, k + 3, L);
          break;
        }
        case dynamics::JointType::Spherical: write_quat(q, k, L); break;
        case dynamics::JointType::Revolute: {
          const Eigen::Vector3d axis = b.axis.template cast<double>();
          q(k) = S(std::remainder(2 * std::atan2(axis.dot(L.vec()), L.w()), 2 * M_PI));
          break;
        }
        case dynamics::JointType::Fixed: break;
      }
    }
  }

  // q -> BodyPose on the skeleton (p sized to the skeleton).
  void to_pose(const ModelT& m, const VecQ& q, pose::BodyPose& p) const noexcept {
    for (int j = 0; j < n_; ++j) {
      const int i = body_[j];
      const dynamics::Body<S>& b = m.bodies[i];
      const int k = b.q_index;
      Eigen::Quaterniond L = Eigen::Quaterniond::Identity();
      switch (b.joint) {
        case dynamics::JointType::Free: L = read_quat(q, k + 3); break;
        case dynamics::JointType::Spherical: L = read_quat(q, k); break;
        case dynamics::JointType::Revolute: L = Eigen::AngleAxisd(double(q(k)), b.axis.template cast<double>()); break;
        case dynamics::JointType::Fixed: break;
      }
      const int par = joint_parent(m, j);
      p.local[j] = ((par < 0 ? L : A_[par] * L) * Ainv_[j]).normalized();
      if (b.joint == dynamics::JointType::Free)
        p.root_position = from_sim_point(Eigen::Vector3d(double(q(k)), double(q(k + 1)), double(q(k + 2)))) - p.local[j] * hip_centre_;
    }
  }

  // v such that integrating from q0 for dt gives q1 (model velocity layout).
  static void velocity(const ModelT& m, const VecQ& q0, const VecQ& q1, S dt, VecV& v) noexcept {
    for (int i = 0; i < m.nb; ++i) {
      const dynamics::Body<S>& b = m.bodies[i];
      const int k = b.q_index, c = b.v_index;
      switch (b.joint) {
        case dynamics::JointType::Free: {
          const dynamics::Quat<S> a = dynamics::read_quat<S>(q0, k + 3), e = dynamics::read_quat<S>(q1, k + 3);
          v.template segment<3>(c) = dynamics::quat_log(dynamics::Quat<S>(a.conjugate() * e)) / dt;
          v.template segment<3>(c + 3) =
              e.toRotationMatrix().transpose() * (q1.template segment<3>(k) - q0.template segment<3>(k)) / dt;
          break;
        }
        case dynamics::JointType::Spherical: {
          const dynamics::Quat<S> a = dynamics::read_quat<S>(q0, k), e = dynamics::read_quat<S>(q1, k);
          v.template segment<3>(c) = dynamics::quat_log(dynamics::Quat<S>(a.conjugate() * e)) / dt;
          break;
        }
        case dynamics::JointType::Revolute:
          v(c) = S(std::remainder(double(q1(k) - q0(k)), 2 * M_PI)) / dt;
          break;
        case dynamics::JointType::Fixed: break;
      }
    }
  }

 private:
  static void write_quat(VecQ& q, int k, const Eigen::Quaterniond& L) noexcept {
    // Keep w >= 0 so that finite differences between neighbouring frames take the short way.
    const double s = L.w() < 0 ? -1.0 : 1.0;
    q(k) = S(s * L.w()); q(k + 1) = S(s * L.x()); q(k + 2) = S(s * L.y()); q(k + 3) = S(s * L.z());
  }
  static Eigen::Quaterniond read_quat(const VecQ& q, int k) noexcept {
    Eigen::Quaterniond r(double(q(k)), double(q(k + 1)), double(q(k + 2)), double(q(k + 3)));
    const double n = r.norm();
    return n > 1e-12 ? Eigen::Quaterniond(r.coeffs() / n) : Eigen::Quaterniond::Identity();
  }

  int joint_parent(const ModelT& m, int j) const noexcept {
    const int pb = m.bodies[body_[j]].parent;
    return pb < 0 ? -1 : joint_[pb];
  }

  std::array<int, MB> body_{}, joint_{};
  std::array<Eigen::Quaterniond, MB> A_{}, Ainv_{};  // A_j and its inverse
  Eigen::Vector3d hip_centre_ = Eigen::Vector3d::Zero();
  int n_ = 0;
  double dy_ = 0;
};

}  // namespace sparsebody::control
