// The default controller of the Neural3Points physics mode: it needs no trained policy (RL policies
// are not shipped) and stands in for the control policy pi of §5. Three parts, per simulation step:
//
//   1. PD targets  u = the predicted pose (q* of every internal joint), refreshed per frame or held
//      until the next control step like the policy's output (per_frame_targets, applied by
//      avatar/n3p_physics.hpp); the simulator's servos (kp = 200, kd = 20, implicit
//      damping) turn it into torques, with velocity targets qd* = qd_ref.
//   2. Feed-forward  tau_ff = RNEA(q_ref, qd_ref, qdd_ref), internal joints only, with qd_ref and
//      qdd_ref finite-differenced from the predicted 30 Hz poses. It removes the servo's steady
//      error under gravity and inertia (a PD servo alone sags by tau / kp). RNEA alone holds the
//      body up by its root; the floor does that instead (stance_support, control/stance_support.hpp):
//      the root wrench w_root = (N, F) it asks for is shared by the feet in contact, and the
//      stance legs carry it, tau_leg(s) -= J_s^T w_s (its moment N too with support_moment).
//   3. Residual wrench  (PD on the root toward the predicted root, world frame)
//        F = clamp(kp_linear (p_ref - p) + kd_linear (v_ref - v+), max_force)
//        N = clamp(kp_angular log(R_ref R^T) + kd_angular (w_ref - w+), max_torque)
//      applied to the root alone by the simulator's root servo (dynamics/root_servo.hpp),
//      its damping at the next velocity v+, w+ implicit inside ABA exactly like the joint servos'
//      kd (D_root = I^A + h K_r), so stiff gains on the 7 kg pelvis are stable at h = 1/120; the
//      applied wrench never exceeds the bounds.
//      It is the help that keeps the character balanced and on the user's path (no learned
//      balance strategy exists without RL). Its magnitude is reported every step
//      (residual_applied() after the step; avatar/n3p_physics.hpp residual(), residual_stats())
//      so users see how much help was needed; max_force defaults to the body weight (the help
//      can hold the body up but never throw it).
// The root reference is interpolated over the 4 substeps of a 30 Hz frame (linear / slerp) and
// lifted out of the floor (ground_reference, ground_lift(): the predicted pose put on the avatar's
// feet is a few cm in the floor, and a root servo toward it pulls the body down on the feet it
// stands on).
// The defaults were chosen on the validation clips with examples/n3p_physics_eval.cpp; the
// figures (each part turned off in turn, the bounds) are in the README (Neural3Points physics
// mode), how they were reached in the commit log.
// Per step: no allocation, no exception.
#pragma once
#include <algorithm>
#include <cmath>

#include "sparsebody/control/floor_penetration.hpp"
#include "sparsebody/control/model_based_controller_config.hpp"
#include "sparsebody/control/n3p_sim_retarget.hpp"
#include "sparsebody/control/residual_wrench.hpp"
#include "sparsebody/control/stance_support.hpp"
#include "sparsebody/dynamics/rnea.hpp"
#include "sparsebody/dynamics/simulator.hpp"

namespace sparsebody::control {

template <class S, int MB, int MD>
class ModelBasedController {
 public:
  using ModelT = dynamics::Model<S, MB, MD>;
  using VecQ = typename ModelT::VecQ;
  using VecV = typename ModelT::VecV;
  using Quat = dynamics::Quat<S>;

  explicit ModelBasedController(const ModelT& m, ModelBasedControllerConfig cfg = {}) : cfg_(cfg), d_(m) {
    root_ = std::max(0, m.root_body());
    support_ = StanceSupport<S, MB, MD>(m, root_);
    tau_ff_.setZero(m.nv);
    v0_.setZero(m.nv);
    v1_.setZero(m.nv);
    a_.setZero(m.nv);
    reset();
  }

  const ModelBasedControllerConfig& config() const noexcept { return cfg_; }
  ModelBasedControllerConfig& config() noexcept { return cfg_; }

  void reset() noexcept {
    tau_ff_.setZero();
    has_ref_ = false;
    last_ = {};
  }

  // The reference of one predicted frame: its configuration q and the two before it (30 Hz, dt),
  // and the foot contact weights (c_L, c_R) of the stance support (the pipeline passes the predicted
  // probabilities, gated by the simulated contacts). Computes qd_ref, qdd_ref, tau_ff and
  // the root reference the next substeps track.
  // (After a (re)start the pipeline repeats the start pose for the missing frames: the reference
  // then accelerates from rest, as the character, placed at rest, does.)
  void set_reference(const ModelT& m, const VecQ& q_prev2, const VecQ& q_prev, const VecQ& q, S dt,
                     const double (&contact)[2]) noexcept {
    N3PSimRetarget<S, MB, MD>::velocity(m, q_prev, q, dt, v1_);
    N3PSimRetarget<S, MB, MD>::velocity(m, q_prev2, q_prev, dt, v0_);
    a_ = (v1_ - v0_) * (S(cfg_.acceleration_scale) / dt);
    const dynamics::Body<S>& r = m.bodies[root_];
    if (cfg_.feedforward_scale != 0) {
      dynamics::rnea(m, d_, q, v1_, a_, tau_ff_);  // leaves d_ with q's kinematics, not world ones
      if (cfg_.stance_support) {
        // The root wrench in the world (RNEA's root entries are body-frame), about the root origin.
        const dynamics::Mat3<S> Rq = dynamics::read_quat<S>(q, r.q_index + 3).toRotationMatrix();
        const Vec3 F = Rq * Vec3(tau_ff_.template segment<3>(r.v_index + 3));
        const Vec3 N = Rq * Vec3(tau_ff_.template segment<3>(r.v_index));
        dynamics::forward_kinematics(m, d_, q, &v1_, true);
        fk_of_q_ = true;
        support_.apply(m, d_, F, N, contact, cfg_.support_moment, tau_ff_);
      }
      tau_ff_ *= S(cfg_.feedforward_scale);
      tau_ff_.template segment<6>(r.v_index).setZero();  // the root is not actuated
      if (!tau_ff_.allFinite()) tau_ff_.setZero();
    } else {
      tau_ff_.setZero();
    }
    const int k = r.q_index;
    // The root target is lifted out of the floor (ground_reference), so the root servo does not
    // pull the body into the floor its feet stand on.
    const S lift = !cfg_.ground_reference ? S(0) : fk_of_q_ ? ground_lift_of_kinematics(m) : ground_lift(m, q);
    fk_of_q_ = false;
    from_p_ = has_ref_ ? p_ref_ : Vec3(q.template segment<3>(k) + lift * Vec3::UnitY());
    from_R_ = has_ref_ ? R_ref_ : dynamics::read_quat<S>(q, k + 3);
    p_ref_ = q.template segment<3>(k) + lift * Vec3::UnitY();
    R_ref_ = dynamics::read_quat<S>(q, k + 3);
    v_ref_ = (q.template segment<3>(k) - q_prev.template segment<3>(k)) / dt;
    w_ref_ = R_ref_ * Vec3(v1_.template segment<3>(r.v_index));
    has_ref_ = true;
  }

  // How far the configuration q's lowest contact point is below the floor (floor_penetration, at
  // most max_ground_lift; 0 if not finite): the predicted pose put on the avatar's feet penetrates
  // it (its feet and soles are not the skeleton's).
  S ground_lift(const ModelT& m, const VecQ& q) noexcept {
    dynamics::forward_kinematics(m, d_, q, static_cast<const VecV*>(nullptr), true);
    return ground_lift_of_kinematics(m);
  }

  // Torques of one simulation step (the feed-forward, written into tau) and the simulator's root
  // servo set to the interpolated root reference (sim.options.root_servo, the root entries of targets()
  // and target_velocities()); the wrench it applies is known after the step: residual_applied(sim).
  // alpha in [0, 1]: how far through the current reference frame this step ends.
  ResidualWrench apply(const ModelT& m, dynamics::Simulator<S, MB, MD>& sim, S alpha, VecV& tau) noexcept {
    tau = tau_ff_;
    last_ = {};
    auto& servo = sim.options.root_servo;
    servo.enabled = false;
    if (!has_ref_) return last_;
    const Vec3 pr = from_p_ + alpha * (p_ref_ - from_p_);
    const Quat Rr = from_R_.slerp(alpha, R_ref_);
    const dynamics::Body<S>& r = m.bodies[root_];
    servo.enabled = true;
    servo.kp_linear = S(cfg_.kp_linear);
    servo.kd_linear = S(cfg_.kd_linear);
    servo.kp_angular = S(cfg_.kp_angular);
    servo.kd_angular = S(cfg_.kd_angular);
    servo.max_force = S(cfg_.max_force);
    servo.max_torque = S(cfg_.max_torque);
    auto& qt = sim.targets();
    qt.template segment<3>(r.q_index) = pr;
    qt(r.q_index + 3) = Rr.w();
    qt.template segment<3>(r.q_index + 4) = Rr.vec();
    auto& vt = sim.target_velocities();  // target body frame: (R_r^T w_ref, R_r^T v_ref)
    vt.template segment<3>(r.v_index) = Rr.conjugate() * w_ref_;
    vt.template segment<3>(r.v_index + 3) = Rr.conjugate() * v_ref_;
    return last_;
  }

  // The residual wrench of the step just taken (call after sim.step): the root servo's applied wrench.
  ResidualWrench residual_applied(const dynamics::Simulator<S, MB, MD>& sim) noexcept {
    if (sim.options.root_servo.enabled) {
      last_.force = double(sim.root_servo_force().norm());
      last_.torque = double(sim.root_servo_torque().norm());
    }
    return last_;
  }
  const ResidualWrench& residual() const noexcept { return last_; }
  const VecV& feedforward() const noexcept { return tau_ff_; }
  const VecV& reference_velocity() const noexcept { return v1_; }

 private:
  using Vec3 = dynamics::Vec3<S>;

  S ground_lift_of_kinematics(const ModelT& m) const noexcept {  // of the configuration in d_
    const S depth = floor_penetration(m, d_);
    return std::isfinite(depth) ? std::min(depth, S(cfg_.max_ground_lift)) : S(0);
  }

  ModelBasedControllerConfig cfg_;
  dynamics::Data<S, MB, MD> d_;  // RNEA workspace
  int root_ = 0;
  StanceSupport<S, MB, MD> support_;
  VecV tau_ff_, v0_, v1_, a_;
  Vec3 p_ref_ = Vec3::Zero(), from_p_ = Vec3::Zero(), v_ref_ = Vec3::Zero(), w_ref_ = Vec3::Zero();
  Quat R_ref_ = Quat::Identity(), from_R_ = Quat::Identity();
  bool has_ref_ = false;
  bool fk_of_q_ = false;  // d_ holds the world kinematics of set_reference's q
  ResidualWrench last_;
};

}  // namespace sparsebody::control
