// The Neural3Points pipeline in normal (physics) mode (Ye et al., SCA 2022, §3, §5-§7, §9): the
// direct-mode pipeline (avatar/n3p_direct.hpp) predicts the user's pose every 30 Hz frame; a
// simulated avatar (character/avatar.hpp: 1.75 m, 63 kg, PD servos kp = 200, kd = 20 on every
// joint, implicit damping) tracks it at 120 Hz (4 substeps per frame):
//
//   TrackerFrame -> Resampler (30 Hz) -> N3PPipeline::step (sanitizer, calibration, predictor, IK)
//     -> reference q_ref(N) (control/n3p_sim_retarget.hpp)
//     -> every 3 frames (10 Hz, §6): a control step sets the PD targets, held until the next one:
//          ControllerKind::Policy: the combined control predictor + learned policy pi
//            (control/n3p_control_predictor.hpp), when policy weights are given;
//          ControllerKind::ModelBased (default, no RL): targets = q_ref of the newest frame,
//            held like the policy's with per_frame_targets = false; by default (it tracks better)
//            refreshed every frame to the reference 2 frames ahead of the tracked one instead;
//            plus per frame velocity targets qd_ref, an inverse-dynamics feed-forward carried by
//            the stance legs and a bounded residual wrench on the root
//            (control/model_based_controller.hpp; its magnitude is reported every step:
//            residual(), residual_stats()); optionally a learned correction of the per-frame
//            targets (set_correction_policy, control/n3p_target_correction.hpp);
//     -> per substep: controller torques + tracker position correction (§6.2, Eq. (19),
//        control/tracker_correction.hpp) -> Simulator::step(1/120)
//     -> once per frame: fall detection (§9, control/fall_detector.hpp) -> reset to the reference
//        (control/n3p_recovery.hpp)
//     -> output: the simulated pose mapped back onto the standard skeleton.
//
// Delay (explicit, §3 / §8.4): the control step at frame t (after the trackers of frame t arrived)
// finds the simulated character at frame t - 3 and gives it the targets of frame t; the character
// reaches them over the next 12 substeps. So the pose output after frame N is the user's pose of
// frame N - 3: kDelayFrames = 3 frames = 0.1 s behind the input. output_frame() / output_time()
// say which input frame (and time stamp) the current pose reproduces; evaluation compares it with
// that frame's ground truth, which is the paper's "shift the generated motion forward by 0.1 s"
// (examples/n3p_physics_eval.cpp does so by default; --no-shift compares with the current frame).
//
// Bad input and failures (defined recovery, tested):
//   - tracker problems (NaN, lost headset or controllers, jumps) are handled by the direct
//     pipeline (held pose / o* substitution / predictor restart); a reference root that jumps by
//     more than `max_reference_jump` in one frame, or a resampler gap, restarts the physics: the
//     character is placed on the next reference pose at rest;
//   - a simulation step that fails (non-finite, velocity limit: dynamics::StepStatus) is rolled
//     back by the simulator; the character is then reset to the reference pose;
//   - a fall (FallDetector) resets the character to the reference pose (with the reference
//     velocity) and the simulation resumes (control/n3p_recovery.hpp);
//   - the output is always finite: a pose that would not be keeps the last one.
// Per frame: no allocation, no exception, no lock (tests/n3p_physics/test_alloc.cpp).
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>

#include "sparsebody/avatar/n3p_direct.hpp"
#include "sparsebody/avatar/n3p_physics_config.hpp"
#include "sparsebody/avatar/n3p_reference_history.hpp"
#include "sparsebody/avatar/pipeline_front_end.hpp"
#include "sparsebody/character/avatar.hpp"
#include "sparsebody/control/fall_detector.hpp"
#include "sparsebody/control/floor_penetration.hpp"
#include "sparsebody/control/model_based_controller.hpp"
#include "sparsebody/control/n3p_control_predictor.hpp"
#include "sparsebody/control/n3p_recovery.hpp"
#include "sparsebody/control/n3p_sim_retarget.hpp"
#include "sparsebody/control/n3p_target_correction.hpp"
#include "sparsebody/control/residual_wrench.hpp"
#include "sparsebody/control/tracker_correction.hpp"
#include "sparsebody/dynamics/simulator.hpp"
#include "sparsebody/nn/half.hpp"
#include "sparsebody/nn/int8.hpp"

namespace sparsebody::avatar {

// W: stored weight type of the networks (T, nn::f16 or nn::q8: see nn/int8.hpp).
template <typename T = float, int HSig = 64, int HLo = 128, int HUp = 128, typename S = float, int MB = 24, int MD = 72,
          typename W = T>
class N3PPhysicsPipeline : public PipelineFrontEnd<N3PPhysicsPipeline<T, HSig, HLo, HUp, S, MB, MD, W>> {
 public:
  using Direct = N3PPipeline<T, HSig, HLo, HUp, W>;
  using Weights = typename Direct::Weights;
  using ModelT = dynamics::Model<S, MB, MD>;
  using VecQ = typename ModelT::VecQ;
  using VecV = typename ModelT::VecV;
  using Sim = dynamics::Simulator<S, MB, MD>;
  using ControlPredictor = control::N3PControlPredictor<T, HSig, HLo, HUp, S, MB, MD, W>;
  using PolicyWeights = typename ControlPredictor::PolicyWeights;
  using Correction = control::N3PTargetCorrection<T, S, MB, MD, character::kDefaultAvatarJointDofs, W>;
  using CorrectionWeights = typename Correction::Weights;
  static constexpr int kDelayFrames = 3;    // 0.1 s at 30 Hz (see the header comment)
  static constexpr int kControlPeriod = 3;  // frames per control step (10 Hz)
  static constexpr int kHistory = 8;        // reference frames kept (ring)
  using History = N3PReferenceHistory<S, MB, MD, kHistory>;

  static Weights load(const std::string& path) { return Direct::load(path); }

  // Model-based controller (default). Throws LoadError when the skeleton does not fit the avatar.
  explicit N3PPhysicsPipeline(const Weights& w, N3PPhysicsConfig cfg = {}) : N3PPhysicsPipeline(w, nullptr, cfg) {}
  // ControllerKind::Policy when `policy` is given (ControlPredictor::load_policy(path)): the
  // combined control predictor and pi set the targets; no feed-forward, no residual wrench.
  N3PPhysicsPipeline(const Weights& w, std::shared_ptr<const PolicyWeights> policy, N3PPhysicsConfig cfg = {})
      : cfg_(cfg),
        direct_(w, cfg.direct),
        model_(character::default_avatar<S, MB, MD>(cfg.avatar)),
        sim_(model_),
        retarget_(control::N3PSimRetarget<S, MB, MD>::from_meta(model_, direct_.meta())),
        controller_(model_, cfg.controller),
        correction_(model_, cfg.correction),
        recovery_(model_, retarget_.body_of(0), cfg.fall, cfg.controller.ground_resets),
        history_(model_.neutral_configuration()) {
    if (policy) control_ = std::make_unique<ControlPredictor>(w, std::move(policy));
    sim_.options.contact.max_passes = cfg.contact_passes;
    q_tmp_ = model_.neutral_configuration();
    tau_.setZero(model_.nv);
    // the front end's resampler gives the ticks; direct mode sanitises them (its step)
    this->start_front_end(direct_.meta().frame_rate, cfg.direct.sanitizer, direct_.skeleton().size());
    reset();
  }

  // A learned correction of the model-based controller's per-frame PD targets (issue 14 item 4:
  // weights_tool.questsim.train --task n3p exports it; load with load_correction). nullptr removes
  // it. Used with ControllerKind::ModelBased and per_frame_targets (the defaults) only. Allocates
  // (the network's buffers): call it at set-up, not per frame. Throws std::invalid_argument if the
  // policy's joint DoFs differ from the avatar's.
  static std::shared_ptr<const CorrectionWeights> load_correction(const std::string& path) { return Correction::load(path); }
  void set_correction_policy(std::shared_ptr<const CorrectionWeights> w) {
    correction_policy_ = w ? std::make_unique<Correction>(std::move(w), model_) : nullptr;
  }
  const Correction* correction_policy() const noexcept { return correction_policy_.get(); }
  long long corrections() const noexcept { return corrections_; }  // frames whose targets the correction set

  // --- calibration (§7), as direct mode (automatic by default) ---------------------------------
  // A calibration change (automatic or explicit) restarts the physics at the next frame: the
  // reference changes size, and the character is placed on it at rest rather than pulled there.
  bool calibrate(const trackers::TrackerFrame& frame) noexcept { return direct_.calibrate(frame); }
  void set_calibration(const features::n3p::N3PCalibration& c) noexcept { direct_.set_calibration(c); }
  void recalibrate() noexcept { direct_.recalibrate(); }
  // For the front end (PipelineFrontEnd): direct mode's, which this pipeline feeds ticks.
  Eigen::Quaterniond head_offset() const noexcept { return direct_.head_offset(); }
  void swap_controller_calibration() noexcept { direct_.swap_controller_calibration(); }
  const features::n3p::N3PCalibration& calibration() const noexcept { return direct_.calibration(); }
  const features::CalibrationReport& calibration_report() const noexcept { return direct_.calibration_report(); }

  // --- running --------------------------------------------------------------------------------
  // One 30 Hz frame (the caller resampled): the direct step, 4 simulation steps, maybe a control step.
  void step(const trackers::TrackerFrame& f, bool gap = false) noexcept {
    if (this->recentres() != recentres_seen_) {  // the front end's stream found one (its push): direct mode sanitises
      recentres_seen_ = this->recentres();
      direct_.tracking_space_moved();
    }
    direct_.step(f, gap);
    ++this->frames_;
    if (gap) restart_ = true;
    if (direct_.calibration_changes() != calibration_seen_ || direct_.stand_ups() != stand_ups_seen_) {
      calibration_seen_ = direct_.calibration_changes();  // a new body, or direct mode restarted at a stand-up
      stand_ups_seen_ = direct_.stand_ups();
      restart_ = true;
    }
    if (!direct_.has_output()) return;
    // Reference of this frame.
    retarget_.to_q(model_, direct_.pose(), q_tmp_);
    if (started_ && (q_tmp_.template head<3>() - history_.q(history_.newest()).template head<3>()).norm() > S(cfg_.max_reference_jump))
      restart_ = true;
    if (!started_ || restart_) {
      start(q_tmp_, f.time);
    } else {
      history_.push(q_tmp_, direct_, retarget_, f.time);
    }
    simulate_frame();
    if ((history_.newest() - history_.first()) % kControlPeriod == 0) control_step();
    output();
  }

  void reset() noexcept {
    direct_.reset();
    this->reset_front_end();
    controller_.reset();
    recovery_.reset();
    if (control_) control_->reset();
    started_ = restart_ = false;
    calibration_seen_ = direct_.calibration_changes();
    stand_ups_seen_ = direct_.stand_ups();
    recentres_seen_ = this->recentres();
    residual_ = {};
    stats_ = {};
    // a fresh simulator (contact and actuation state included, options kept) and torques, so that
    // a reset instance continues bit for bit like a new one (tests/determinism)
    sim_ = Sim(model_, sim_.options);
    tau_.setZero();
  }

  // --- results --------------------------------------------------------------------------------
  // pose(), world(), has_output() (PipelineFrontEnd): the simulated pose on the standard skeleton
  // (metres), kDelayFrames behind the input.
  // Input frame (counted from the last physics start) and time stamp the output reproduces.
  long long output_frame() const noexcept { return sim_frame_; }
  double output_time() const noexcept { return out_time_; }
  static constexpr double delay_seconds() noexcept { return kDelayFrames / 30.0; }

  // The reference configuration (retargeted prediction) the character tracks now (frame output_frame()).
  const VecQ& reference() const noexcept { return history_.q(history_.first() + sim_frame_); }
  const control::ResidualWrench& residual() const noexcept { return residual_; }  // last step
  const control::ResidualStats& residual_stats() const noexcept { return stats_; }
  void clear_residual_stats() noexcept { stats_ = {}; }
  long long falls() const noexcept { return recovery_.falls(); }  // fall resets
  long long falls(control::FallReason why) const noexcept { return recovery_.falls(why); }
  long long sim_failures() const noexcept { return recovery_.sim_failures(); }  // rolled-back steps -> reset
  long long restarts() const noexcept { return recovery_.restarts(); }          // physics (re)starts
  long long stand_ups() const noexcept { return direct_.stand_ups(); }  // direct mode's (each restarts both)
  ControllerKind controller_kind() const noexcept { return control_ ? ControllerKind::Policy : ControllerKind::ModelBased; }
  const ControlPredictor* control_predictor() const noexcept { return control_.get(); }
  ControlPredictor* control_predictor() noexcept { return control_.get(); }  // e.g. its tracker_ik switch
  long long policy_steps() const noexcept { return policy_steps_; }  // control steps the policy set the targets

  const Direct& direct() const noexcept { return direct_; }  // the reference (direct mode, no delay)
  const Sim& simulator() const noexcept { return sim_; }
  const ModelT& model() const noexcept { return model_; }
  const control::N3PSimRetarget<S, MB, MD>& retarget() const noexcept { return retarget_; }
  // The simulated character's proportions are the standard skeleton's (scaled by the user's size):
  // skeleton() = standard_skeleton(), whatever the reference's arm fit does.
  const pose::Skeleton& skeleton() const noexcept { return direct_.standard_skeleton(); }
  const pose::Skeleton& standard_skeleton() const noexcept { return direct_.standard_skeleton(); }
  const pose::BodyProportions& body_proportions() const noexcept { return prop_; }
  // Not used: the simulated character keeps the standard proportions (the demo calls it for every
  // pipeline).
  void set_body_proportions(const pose::BodyProportions&) noexcept {}
  const pose::JointMap& joint_map() const noexcept { return direct_.joint_map(); }
  // Foot (0 left, 1 right) of the simulated character touching the ground (an active contact on its
  // Foot or Toes body in the last step): the physical contact, not the predicted one.
  bool contact(int foot) const noexcept {
    const int f = retarget_.body_of(direct_.joint_map()[foot ? pose::Role::FootR : pose::Role::FootL]);
    const int t = retarget_.body_of(direct_.joint_map()[foot ? pose::Role::ToeR : pose::Role::ToeL]);
    for (int k = 0; k < sim_.num_contacts(); ++k) {
      const auto& c = sim_.contact_at(k);
      if (c.active && (c.body == f || c.body == t)) return true;
    }
    return false;
  }
  const predict::N3PMeta& meta() const noexcept { return direct_.meta(); }
  double user_scale() const noexcept { return direct_.user_scale(); }
  const N3PPhysicsConfig& config() const noexcept { return cfg_; }

  // Lowest point of the simulated body below the floor (m, >= 0): ground penetration.
  double penetration() const noexcept { return double(control::floor_penetration(model_, sim_.data())); }

 private:
  void start(const VecQ& q, double time) noexcept {
    history_.start(started_ ? history_.newest() + 1 : 0, q, direct_, retarget_, time);
    recovery_.start(model_, sim_, controller_, q);
    sim_.targets() = q;
    controller_.reset();
    if (control_) control_->start(direct_.trackers(), direct_.trackers_present());
    started_ = true;
    restart_ = false;
  }

  void simulate_frame() noexcept {
    const long long F = std::max(history_.first(), history_.newest() - kDelayFrames);  // the frame the character reaches now
    sim_frame_ = F - history_.first();
    const S dt = S(1.0 / 30), h = dt / S(cfg_.substeps);
    const auto& hd = history_.at(F);
    double support[2] = {hd.contact[0], hd.contact[1]};
    if (cfg_.controller.support_on_contact)  // stance support only for a foot the simulated character stands on
      for (int s = 0; s < 2; ++s) support[s] = contact(s) ? support[s] : 0.0;
    controller_.set_reference(model_, history_.q(F - 2), history_.q(F - 1), history_.q(F), dt, support);
    if (cfg_.controller.per_frame_targets && !control_) {
      sim_.targets() = history_.q(F + cfg_.controller.target_lead);
      if (correction_policy_ &&
          correction_policy_->correct(model_, retarget_, sim_.data(),
                                      {&history_.q(F - 1), &history_.q(F), &history_.q(F + 1), &history_.q(F + 2), &history_.q(F + 3)},
                                      sim_.targets()))
        ++corrections_;
    }
    if (!control_ && cfg_.controller.velocity_targets) sim_.target_velocities() = controller_.reference_velocity();
    out_time_ = hd.time;
    const bool policy = control_ != nullptr;
    for (int k = 0; k < cfg_.substeps; ++k) {
      const S alpha = S(k + 1) / S(cfg_.substeps);
      if (policy) {
        tau_.setZero();
        sim_.options.root_servo.enabled = false;
        residual_ = {};
      } else {
        controller_.apply(model_, sim_, alpha, tau_);
      }
      correction_.apply(model_, sim_.data(), hd.hand, hd.hand_present, tau_);
      sim_.torques() = tau_;
      if (sim_.step(h) != dynamics::StepStatus::Ok) {
        recovery_.after_failure(model_, sim_, controller_, history_.q(F - 1), history_.q(F));
        break;
      }
      if (!policy) residual_ = controller_.residual_applied(sim_);
      stats_.add(residual_);
    }
    // §9: loss of balance -> reset to the predicted pose, resume.
    recovery_.check(model_, sim_, controller_, history_.q(F - 1), history_.q(F));
  }

  // 10 Hz: the targets held for the next kControlPeriod frames.
  void control_step() noexcept {
    if (control_) {
      if (history_.newest() - history_.first() < kControlPeriod) return;  // the start pose's targets until 3 frames exist
      for (int k = 0; k < 3; ++k) {
        const auto& h = history_.at(history_.newest() - 2 + k);
        ctl_o_[k] = h.trackers;
        ctl_present_[k] = h.present;
      }
      if (control_->control(ctl_o_, ctl_present_, model_, sim_.data(), retarget_, sim_.targets())) ++policy_steps_;
      return;
    }
    sim_.targets() = history_.q(history_.newest());  // model-based: u = the newest predicted pose
  }

  void output() noexcept {
    retarget_.to_pose(model_, sim_.q(), this->out_.pose());
    pose::forward_kinematics(direct_.standard_skeleton(), this->out_.pose(), this->out_.world());
    if (!this->out_.commit()) restart_ = true;  // the last finite pose is kept; the physics restarts
  }

  N3PPhysicsConfig cfg_;
  Direct direct_;
  std::unique_ptr<ControlPredictor> control_;
  std::unique_ptr<Correction> correction_policy_;
  long long corrections_ = 0;
  features::n3p::TrackerSet ctl_o_[3];
  std::array<bool, 3> ctl_present_[3];
  long long policy_steps_ = 0;
  ModelT model_;
  Sim sim_;
  control::N3PSimRetarget<S, MB, MD> retarget_;
  control::ModelBasedController<S, MB, MD> controller_;
  control::TrackerCorrection<S, MB, MD> correction_;
  control::N3PRecovery<S, MB, MD> recovery_;
  History history_;
  VecQ q_tmp_;
  VecV tau_;
  long long sim_frame_ = 0;
  double out_time_ = 0;
  bool started_ = false, restart_ = false;
  long long calibration_seen_ = 0;  // direct_.calibration_changes() already restarted for
  long long stand_ups_seen_ = 0;    // direct_.stand_ups() already restarted for
  int recentres_seen_ = 0;          // this->recentres() already passed on to direct mode
  control::ResidualWrench residual_;
  control::ResidualStats stats_;
  pose::BodyProportions prop_{};  // standard: the simulated character
};

// The shipped configurations: the paper's network sizes (the default weights, examples/weights/n3p)
// driving the default avatar in float, the networks' weights stored as W.
template <typename W = float>
using N3PPhysicsDefaultSizes = N3PPhysicsPipeline<float, 64, 128, 128, float, 24, 72, W>;
using N3PPhysicsDefault = N3PPhysicsDefaultSizes<float>;
using N3PPhysicsF16 = N3PPhysicsDefaultSizes<nn::f16>;  // half the weight bytes
using N3PPhysicsQ8 = N3PPhysicsDefaultSizes<nn::q8>;    // int8 weights, approximate (nn/int8.hpp)

}  // namespace sparsebody::avatar
