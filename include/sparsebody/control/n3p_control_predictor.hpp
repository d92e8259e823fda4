// Neural3Points combined control predictor (SCA 2022, §6) with the learned control policy pi (§5):
// the alternative to the default model-based controller (control/model_based_controller.hpp) in
// the physics pipeline (avatar/n3p_physics.hpp, ControllerKind::Policy). Once every 3 tracker
// frames (10 Hz), at frame t, with the simulated character at frame t - 3:
//
//   1. the pose predictor restarts from its committed state (GRU states, heading h^{t-3}: "the
//      previous prediction of the user's heading is employed as the initial heading") with the
//      joint states of g_lo / g_up replaced by the simulated character's (positions, velocities,
//      rotations in h^{t-3}: "the initial pose of this prediction is extracted from the current
//      state of the simulated character"); contacts and z are kept from the prediction;
//   2. it runs over the 3 received frames t-2, t-1, t (its state after frame t is committed for the
//      next control step), then over 6 forecast frames t+1 .. t+6 (Eq. (18): o^t = delta_o + o^{t-1},
//      delta_o the average offset between consecutive received frames; applied to the positions,
//      orientations held): 9 predicted states;
//   3. IK to the trackers (§6, "in the way similar to [ZSKS18]"): in each predicted state the policy
//      sees, each arm (UpperArm -> LowerArm -> Hand) is put on its controller (received or
//      forecast, Eq. (18)) by the analytic two-bone IK of direct mode (pose/ik.hpp): the hand
//      joint goes to the controller position (clamped to the arm's reach), the elbow stays in
//      the predicted bend plane; UpperArm and LowerArm rotations are swung to the new bones, the
//      hand keeps its predicted orientation, velocities stay as predicted. A controller that is
//      not present (o* substituted) is not a target. The IK edits the copies that go into s, not
//      the predictor's own state (the autoregressive rollout stays the network's);
//   4. s = {x_t, g_t+1, g_t+2, g_t+3} (control/n3p_policy_input.hpp) in h_ref = h^{t-3}, with
//      g_t+k the predictions 3k frames after the simulation time (frames t, t+3, t+6);
//   5. u = pi(s): target local rotations of the 20 internal joints -> PD targets (q layout) through
//      control/n3p_sim_retarget.hpp, held for the next 12 simulation steps.
// Per control step: no allocation, no exception (a non-finite policy output keeps the previous
// targets and returns false).
#pragma once
#include <array>
#include <memory>
#include <string>

#include "sparsebody/predict/n3p_predictor.hpp"
#include "sparsebody/control/n3p_policy_input.hpp"
#include "sparsebody/control/n3p_sim_retarget.hpp"
#include "sparsebody/dynamics/kinematics.hpp"
#include "sparsebody/networks/policy_nets.hpp"
#include "sparsebody/pose/ik.hpp"

namespace sparsebody::control {

// W: stored weight type of the predictor and policy networks (T, nn::f16 or nn::q8).
template <typename T, int HSig, int HLo, int HUp, typename S, int MB, int MD, typename W = T>
class N3PControlPredictor {
 public:
  using Predictor = predict::N3PPredictor<T, HSig, HLo, HUp, W>;
  using PolicyNet = networks::N3PPolicyNet<T, n3p_policy::kPolicyIn, n3p_policy::kPolicyOut, 256, W>;
  using PolicyWeights = nn::NetworkWeights<PolicyNet>;
  using ModelT = dynamics::Model<S, MB, MD>;
  using VecQ = typename ModelT::VecQ;
  static constexpr int kRollout = 9, kReceived = 3;

  static std::shared_ptr<const PolicyWeights> load_policy(const std::string& path) {
    return PolicyWeights::load(path, networks::kN3PPolicyKind);
  }

  N3PControlPredictor(const typename Predictor::Weights& w, std::shared_ptr<const PolicyWeights> policy)
      : pred_(w), pi_(std::move(policy)) {
    pose_.resize(pred_.skeleton().size());
    const char* arm[2][3] = {{"UpperArm_L", "LowerArm_L", "Hand_L"}, {"UpperArm_R", "LowerArm_R", "Hand_R"}};
    for (int side = 0; side < 2; ++side)
      for (int c = 0; c < 3; ++c) {
        arm_[side][c] = -1;
        for (int i = 0; i < features::n3p::kUpperJoints; ++i)
          if (std::string(features::n3p::kUpperNames[i]) == arm[side][c]) arm_[side][c] = i;
      }
    reset();
  }

  // IK of the rollout's arms to the trackers (step 3); on by default.
  bool tracker_ik = true;

  void reset() noexcept {
    pred_.reset();
    started_ = false;
  }

  // At a physics (re)start: the committed state after frame `o` (the trackers of that frame).
  void start(const features::n3p::TrackerSet& o, const std::array<bool, 3>& present) noexcept {
    pred_.reset();
    started_ = pred_.step(o, present);
    if (started_) pred_.save(committed_);
  }
  bool started() const noexcept { return started_; }

  // One control step. o[k], present[k]: the trackers of frames t-2, t-1, t (k = 0, 1, 2). The
  // character: model, simulator data and retarget. Writes the PD targets (spherical / revolute
  // entries of `targets`); returns false (targets untouched) when it cannot.
  bool control(const features::n3p::TrackerSet (&o)[kReceived], const std::array<bool, 3> (&present)[kReceived],
               const ModelT& m, const dynamics::Data<S, MB, MD>& d, const N3PSimRetarget<S, MB, MD>& rt,
               VecQ& targets) noexcept {
    if (!started_) return false;
    namespace n3p = features::n3p;
    const pose::Skeleton& sk = pred_.skeleton();
    const predict::N3PMeta& meta = pred_.meta();
    // 1. the committed state with the character's joint states, in h^{t-3} = h_ref.
    work_ = committed_;
    const features::HeadingFrame href = committed_.h;
    for (int j = 0; j < sk.size(); ++j) rt.joint_state(d, j, p_[j], v_[j], R_[j]);
    auto write = [&](T* g, int K, int i, int j) {
      const Eigen::Vector3d p = href.point_to_local(p_[j]), v = href.vector_to_local(v_[j]);
      const Eigen::Matrix3d R = href.rotation_to_local(R_[j]);
      for (int a = 0; a < 3; ++a) {
        g[3 * i + a] = static_cast<T>(p[a]);
        g[3 * K + 3 * i + a] = static_cast<T>(v[a]);
      }
      pose::to6d<T>(R, g + 6 * K + 6 * i);
    };
    for (int i = 0; i < n3p::kLowerJoints; ++i) write(work_.glo, n3p::kLowerJoints, i, meta.lower[i]);
    for (int i = 0; i < n3p::kUpperJoints; ++i) write(work_.gup, n3p::kUpperJoints, i, meta.upper[i]);
    pred_.restore(work_);
    // 2. three received frames, then six forecast ones (Eq. (18)).
    for (int k = 0; k < kRollout; ++k) {
      features::n3p::TrackerSet x;
      std::array<bool, 3> pr{true, true, true};
      if (k < kReceived) {
        x = o[k];
        pr = present[k];
      } else {
        x = last_;
        for (int a = 0; a < 3; ++a) x[a].p += delta_[a];
        pr = present[kReceived - 1];
      }
      if (!pred_.step(x, pr)) {
        pred_.restore(committed_);  // keep the committed state; targets unchanged
        return false;
      }
      if (k == 0) {
        for (int a = 0; a < 3; ++a) delta_[a] = 0.5 * (o[kReceived - 1][a].p - o[0][a].p);  // average offset
      }
      last_ = x;
      if (k == kReceived - 1) pred_.save(committed_);
      rollout_h_[k] = pred_.heading();
      std::copy(pred_.g_lo(), pred_.g_lo() + n3p::kGlo, rollout_glo_[k].begin());
      std::copy(pred_.g_up(), pred_.g_up() + n3p::kGup, rollout_gup_[k].begin());
      if (tracker_ik && k % 3 == 2) arms_to_trackers(rollout_h_[k], x, pr, rollout_gup_[k]);  // the states s uses
    }
    // 3. s in h_ref: x_t, then the predictions 3, 6, 9 frames after the simulation time.
    n3p_policy::character_block(href, p_.data(), v_.data(), R_.data(), s_.data());
    for (int k = 0; k < n3p_policy::kFuture; ++k) {
      const int f = 3 * (k + 1) - 1;
      n3p_policy::predicted_block(href, rollout_h_[f], rollout_glo_[f].data(), rollout_gup_[f].data(), meta.lower.data(),
                                  meta.upper.data(), s_.data() + n3p_policy::kBlock * (1 + k));
    }
    // 4. u = pi(s) -> targets.
    const T* u = pi_.step(s_.data());
    bool finite = true;
    for (int i = 0; i < n3p_policy::kPolicyOut; ++i) finite &= static_cast<bool>(std::isfinite(u[i]));
    if (!finite) return false;
    pose_.root_position.setZero();
    pose_.local[0].setIdentity();
    for (int j = 1; j < sk.size(); ++j) pose_.local[j] = Eigen::Quaterniond(n3p_policy::target_rotation(u, j));
    q_tmp_ = targets;
    rt.to_q(m, pose_, q_tmp_);
    const int root_q = m.bodies[rt.body_of(0)].q_index;
    q_tmp_.template segment<7>(root_q) = targets.template segment<7>(root_q);  // the root is not a servo
    targets = q_tmp_;
    return true;
  }

  const std::array<T, n3p_policy::kPolicyIn>& policy_input() const noexcept { return s_; }
  // Rollout state k (0..8) of the last control step: heading and g_up (after the IK for k = 2, 5, 8).
  const features::HeadingFrame& rollout_heading(int k) const noexcept { return rollout_h_[k]; }
  const std::array<T, features::n3p::kGup>& rollout_g_up(int k) const noexcept { return rollout_gup_[k]; }
  // World position of upper joint i (J_up order) in rollout state k.
  Eigen::Vector3d rollout_upper_position(int k, int i) const noexcept {
    const T* p = rollout_gup_[k].data() + features::n3p::UpperBlock::pos(i);
    return rollout_h_[k].point_to_world(Eigen::Vector3d(double(p[0]), double(p[1]), double(p[2])));
  }
  // Index in J_up of UpperArm, LowerArm, Hand (c = 0, 1, 2) of an arm (side 0 left, 1 right).
  int arm_joint(int side, int c) const noexcept { return arm_[side][c]; }
  const Predictor& predictor() const noexcept { return pred_; }

 private:
  using Snapshot = typename Predictor::Snapshot;

  // Step 3: two-bone IK of each present controller's arm in g (heading h): pose::limb_to as direct
  // mode's arms (bent in the predicted plane, Composed swings, here on 6D rotation matrices).
  void arms_to_trackers(const features::HeadingFrame& h, const features::n3p::TrackerSet& x, const std::array<bool, 3>& present,
                        std::array<T, features::n3p::kGup>& g) const noexcept {
    using B = features::n3p::UpperBlock;
    for (int side = 0; side < 2; ++side) {
      if (!present[1 + side] || arm_[side][0] < 0 || arm_[side][1] < 0 || arm_[side][2] < 0) continue;
      const Eigen::Vector3d target = h.point_to_local(x[1 + side].p);
      if (!target.allFinite()) continue;
      Eigen::Vector3d p[3];
      Eigen::Matrix3d R[2];
      for (int c = 0; c < 3; ++c) {
        const T* q = g.data() + B::pos(arm_[side][c]);
        p[c] = Eigen::Vector3d(double(q[0]), double(q[1]), double(q[2]));
      }
      for (int c = 0; c < 2; ++c) R[c] = pose::from6d(g.data() + B::rot(arm_[side][c]));
      const pose::LimbSolution<Eigen::Matrix3d> ik = pose::limb_to(p[0], p[1], p[2], R[0], R[1], target, p[1] - p[0]);
      if (!ik.b.allFinite() || !ik.c.allFinite() || !ik.upper.allFinite() || !ik.lower.allFinite()) continue;
      for (int a = 0; a < 3; ++a) {
        g[B::pos(arm_[side][1]) + a] = static_cast<T>(ik.b[a]);
        g[B::pos(arm_[side][2]) + a] = static_cast<T>(ik.c[a]);
      }
      pose::to6d<T>(ik.upper, g.data() + B::rot(arm_[side][0]));
      pose::to6d<T>(ik.lower, g.data() + B::rot(arm_[side][1]));
    }
  }
  Predictor pred_;
  nn::Network<PolicyNet> pi_;
  Snapshot committed_, work_;
  bool started_ = false;
  features::n3p::TrackerSet last_{};
  Eigen::Vector3d delta_[3] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  std::array<Eigen::Vector3d, MB> p_{}, v_{};
  std::array<Eigen::Matrix3d, MB> R_{};
  std::array<features::HeadingFrame, kRollout> rollout_h_{};
  std::array<std::array<T, features::n3p::kGlo>, kRollout> rollout_glo_{};
  std::array<std::array<T, features::n3p::kGup>, kRollout> rollout_gup_{};
  std::array<T, n3p_policy::kPolicyIn> s_{};
  pose::BodyPose pose_;
  VecQ q_tmp_;
  int arm_[2][3] = {};  // J_up index of UpperArm, LowerArm, Hand per side
};

}  // namespace sparsebody::control
