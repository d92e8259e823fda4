// The LoBSTr avatar pipeline (Yang et al., Eurographics 2021): tracker frames in, a full-body pose
// on the standard skeleton out.
//
//   TrackerFrame (any rate) -> Resampler (model rate) -> TrackerSanitizer (bad input)
//     -> Calibration (device offsets, orientation offsets, height scale; found automatically from
//        standing windows, features/auto_calibration.hpp) -> LoBSTrFeatures (37) -> LoBSTrNet (GRU)
//     -> lower body: 8 local rotations (6D) under the hips placed by the pelvis tracker
//     -> contacts -> FootLock + leg IK (§3.4.1);  upper body: spine/head aim + two-bone arm IK
//        (avatar/lobstr_upper_body.hpp).
//
// Run modes (Config::mode):
//   Streaming  one GRU step per frame with the hidden state carried over (cost: 1 step/frame).
//              Training used chunks of 64 frames with a loss on every frame, so long runs are in
//              distribution only as far as the GRU generalises; the state is reset after gaps.
//   Window     each frame re-runs the last N = 1 s of features from a zero state, exactly as in
//              the paper's training and inference (§3.2, Δi = 1 s); N times the cost.
// Calibration: by default automatic (Config::calibration): until the user has stood still for a
// second the pipeline runs with the default body (s = 1, half-turn offsets, the device offsets of
// Config::devices) and calibration_report() says so; each accepted standing window recalibrates and
// restarts the feature history (no velocity spike). calibrate(frame) (a T-pose or a standing
// frame) and set_calibration(c) are explicit: used as given, the search stops until recalibrate().
// Per frame: no allocation, no exception, no lock. Everything is sized at construction.
#pragma once
#include <algorithm>
#include <array>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "sparsebody/avatar/lobstr_upper_body.hpp"
#include "sparsebody/avatar/pipeline_front_end.hpp"
#include "sparsebody/core/one_copy.hpp"
#include "sparsebody/features/auto_calibration.hpp"
#include "sparsebody/features/calibration.hpp"
#include "sparsebody/features/device_model.hpp"
#include "sparsebody/features/lobstr_features.hpp"
#include "sparsebody/networks/lobstr_net.hpp"
#include "sparsebody/nn/half.hpp"
#include "sparsebody/nn/int8.hpp"
#include "sparsebody/nn/network.hpp"
#include "sparsebody/pose/arm_reach.hpp"
#include "sparsebody/pose/body_pose.hpp"
#include "sparsebody/pose/body_proportions.hpp"
#include "sparsebody/pose/contact.hpp"
#include "sparsebody/pose/foot_roll.hpp"
#include "sparsebody/pose/ik.hpp"
#include "sparsebody/pose/joint_map.hpp"
#include "sparsebody/pose/rotation6d.hpp"
#include "sparsebody/trackers/stand_up.hpp"
#include "sparsebody/trackers/stillness.hpp"
#include "sparsebody/predict/lobstr_meta.hpp"

namespace sparsebody::avatar {

enum class RunMode { Streaming, Window };

struct LoBSTrConfig {
  RunMode mode = RunMode::Streaming;
  int window = 0;                  // window-mode frames; 0: 1 s at the model rate
  double contact_threshold = 0.5;  // P(contact) above which a foot is in contact
  double lock_max_drift = 0.10;    // m: release a lock the network's toe has left this far (standard scale)
  bool contact_ik = true;          // §3.4.1 post-processing
  // A locked (or releasing) toe whose ankle the leg cannot reach rolls the foot over the toe by the
  // least angle that reaches, at most this (rad; pose/foot_roll.hpp; 0: off), as a heel lifts at the
  // end of a stance, instead of the leg stretching and the toe sliding. All 301 validation clips (offdist
  // nominal): MPJPE 3.15 -> 3.12 cm, foot skating 6.59 -> 6.53 cm/s.
  double max_foot_roll = 1.0;
  // A lock released for drift or reach while the network's contact stays on re-plants the foot
  // where the network has it after the 10-frame blend (pose::FootLock::set_replant), instead of
  // leaving it free until the contact goes off once: 3.5 % of the validation clips' contact frames
  // were such free feet, sliding at 52 cm/s. Foot skating 6.53 -> 5.86 cm/s (nominal), CMU clips
  // 78 -> 62 cm/s; MPJPE +0.04 / -0.22 cm.
  bool replant_released_feet = true;
  // While the user stands still (trackers::Stillness on the headset) locked feet stay locked and a
  // foot the network gives at least still_contact_threshold locks too: no creeping feet.
  bool hold_feet_when_still = true;
  double still_contact_threshold = 0.25;
  // ... and a foot released while walking (held off until its contact goes off once) locks again
  // once the network moves it slower than this (m/s; a foot it moves faster steps while the head
  // stays: it stays free). offdist, every 5th clip: feet while still 0.96 -> 0.22 cm/s (LoBSTr
  // nominal), 4.74 -> 3.21 (csv); without the speed limit 0.20 / 2.82 but +0.12 cm nominal MPJPE.
  double still_rearm_speed = 0.12;
  trackers::StillnessConfig stillness{};
  // A stand-up (the head back near its standing height after sitting or crouching) restarts the
  // network and lets go of the foot locks (trackers/stand_up.hpp).
  trackers::StandUpConfig stand_up{};
  bool upper_body_ik = true;
  trackers::SanitizerConfig sanitizer{};
  features::DeviceModel devices{};                 // device -> joint offsets (DeviceModel::none(): trackers at the joints)
  features::AutoCalibrationConfig calibration{};   // the standing-window search (enabled by default)
  features::ScaleFrom scale_from = features::ScaleFrom::Head;  // explicit calibrate(frame): head or pelvis height
  // Any body (pose/body_proportions.hpp): the output skeleton's legs sized by the pelvis tracker's
  // standing height (Calibration::hips_height), the torso by what is left up to the head, the hips
  // at the tracker. The network's input is unchanged (it sees the standard hips height). The leg
  // ratio is kept within 1 +- leg_ratio_limit (the training bodies' +-8 % and the belt's placement).
  bool fit_legs = true;
  double leg_ratio_limit = 0.12;
  // ... and its arms lengthened where the controllers are seen beyond their reach (pose/arm_reach.hpp).
  pose::ArmReachConfig arm_reach{};
};

// W: the network's stored weight type: T, nn::f16 (half the bytes) or nn::q8 (int8, a quarter;
// see nn/int8.hpp and the README for what each costs in accuracy).
template <typename T = float, int Hidden = 256, int Latent = 128, typename W = T>
class LoBSTrPipeline : public PipelineFrontEnd<LoBSTrPipeline<T, Hidden, Latent, W>> {
  using Base = PipelineFrontEnd<LoBSTrPipeline>;

 public:
  using Net = networks::LoBSTrNet<T, Hidden, Latent, features::kLoBSTrFeatureCount, W>;
  using Weights = nn::NetworkWeights<Net>;
  static constexpr int kFeatures = features::kLoBSTrFeatureCount;
  static constexpr int kHidden = Hidden, kLatent = Latent;

  static std::shared_ptr<const Weights> load(const std::string& path) { return Weights::load(path, networks::kLoBSTrKind); }

  explicit LoBSTrPipeline(std::shared_ptr<const Weights> w, LoBSTrConfig cfg = {})
      : cfg_(cfg), meta_(predict::LoBSTrMeta::from(w->info())), net_(w) {
    const pose::Skeleton& s = meta_.skeleton;
    map_ = pose::JointMap::from_names(s, w->info().source);
    body_ = s;  // the user's proportions are written into this copy (no allocation later)
    reach_ = pose::ArmReach(cfg.arm_reach);
    for (int side = 0; side < 2; ++side) arm_length_[side] = pose::arm_length(s, map_[side == 0 ? pose::Role::HandL : pose::Role::HandR]);
    F_hips_T_ = pose::hips_tracker_frame(s, map_).transpose();
    this->start_front_end(meta_.frame_rate, cfg.sanitizer, s.size());
    still_ = trackers::Stillness(cfg.stillness);
    stand_up_ = trackers::StandUp(cfg.stand_up);
    for (pose::FootLock& l : lock_) {
      l.set_hold_rearm_step(cfg_.still_rearm_speed / meta_.frame_rate);
      l.set_replant(cfg_.replant_released_feet);
    }
    window_ = cfg_.window > 0 ? cfg_.window : static_cast<int>(meta_.frame_rate + 0.5);
    if (cfg_.mode == RunMode::Window) ring_.assign(static_cast<std::size_t>(window_) * kFeatures, T(0));
    upper_ = LoBSTrUpperBody(s, map_);
    auto_ = features::AutoCalibration(cfg.devices, meta_.standing_head_height, cfg.calibration, meta_.standing_hips_height);
    calib_ = auto_.calibration();
    reset();
  }

  // --- calibration -------------------------------------------------------------------------
  // Explicit calibrations: used as given, the automatic search stops until recalibrate(). A change
  // restarts the feature history (as a reset does).
  void set_calibration(const features::Calibration& c) noexcept {
    calib_ = c;
    auto_.set_explicit(c, features::CalibrationSource::Application);
    fit_body();
    reset_state();
  }
  const features::Calibration& calibration() const noexcept { return calib_; }
  // From one frame of the user upright facing forward (a T-pose, paper §4.2, or a standing frame);
  // false (unchanged) when the frame cannot be used.
  bool calibrate(const trackers::TrackerFrame& frame) noexcept {
    features::Calibration c;
    if (!c.from_tpose(frame, meta_.standing_hips_height, meta_.standing_head_height, cfg_.devices, cfg_.scale_from)) return false;
    calib_ = c;
    auto_.set_explicit(c, features::CalibrationSource::Explicit, frame.time);
    fit_body();
    reset_state();
    return true;
  }
  // The user's proportions when the application knows them (an avatar rig; the mocap skeleton that
  // drives trackers at the joints: pose::proportions_by_leg), used instead of the belt's estimate
  // (no hips lift: the pelvis tracker is taken as the hips) until recalibrate();
  // BodyProportions{} goes back to the estimate. Ratios held within [0.75, 1.33].
  void set_body_proportions(const pose::BodyProportions& b) noexcept {
    explicit_prop_ = b.sane();
    explicit_body_ = !explicit_prop_.standard();
    reach_.reset(arm_start());  // the reach lengthens from the application's arms
    fit_body();
  }
  // Forget the calibration (explicit or automatic) and search for standing windows again.
  void recalibrate() noexcept {
    auto_.recalibrate();
    calib_ = auto_.calibration();
    explicit_body_ = false;
    reach_.reset(arm_start());
    fit_body();
    reset_state();
  }
  // What the calibration in use is based on (default body, automatic, explicit, refused).
  const features::CalibrationReport& calibration_report() const noexcept { return auto_.report(); }
  // For the front end (PipelineFrontEnd): the headset's o_head, and the controllers exchanged by
  // the tracker stream from the next tick on (their orientation offsets follow the devices).
  Eigen::Quaterniond head_offset() const noexcept { return calib_.offset[0]; }
  void swap_controller_calibration() noexcept {
    calib_.swap_controllers();
    auto_.swap_controllers();
  }
  const features::AutoCalibration& auto_calibration() const noexcept { return auto_; }

  // --- running ------------------------------------------------------------------------------
  // push(frame) (any rate, PipelineFrontEnd) runs step once per model tick.
  // One model frame (the caller does the resampling). `restart`: state reset before this frame.
  void step(const trackers::TrackerFrame& f, bool restart = false) noexcept {
    if (begin_step(f, restart)) end_step(run_network());
  }

  // step() in two halves, for stepping many users' networks in one call (avatar/lobstr_batch.hpp):
  // begin_step does everything before the network and returns its input (the 37 features), or
  // nullptr when the frame is not usable (then the frame is done); end_step(y) takes the
  // network's outputs for that input and does the rest. step(f) = begin_step(f), then
  // end_step(run_network()). The network's state is network() (Streaming mode: one step per frame).
  SPARSEBODY_ONE_COPY const T* begin_step(const trackers::TrackerFrame& f, bool restart = false) noexcept {
    const trackers::SanitizedFrame& s = stream_.sanitize(f);
    if (restart || s.reset) {
      reset_state();
      auto_.break_window();
    }
    ++frames_;
    if (!s.usable) { out_.invalidate(); return nullptr; }
    const bool first = auto_.report().status != features::CalibrationStatus::Calibrated;
    if (auto_.push(f.time, s.pose, s.measured)) {  // a new calibration found while running
      const double k = auto_.calibration().scale / calib_.scale;
      calib_ = auto_.calibration();
      // arms measured at another size were measured on another body (the default one)
      if (!features::refines_size(k)) reach_.reset(arm_start());
      fit_body();
      // A refinement (the size within 5 %): the feature history starts again (no velocity spike
      // from the new offsets and scale), the GRU carries on (but see `first`), and the foot locks and the stillness
      // detector move with the standard-scale world (x k on the ground), so the avatar's feet stay
      // where they are on the user's floor. A larger change restarts everything: the GRU's state
      // and the locks described another body (keeping them made feet skate on 1.90 m bodies).
      // offdist, every 5th clip: feet while standing still 2.24 -> 0.99 cm/s in device sessions.
      // Either way the stillness detector carries on, and says still if the calibrator's standing
      // window is not over yet (restarting it left the feet unheld for ~0.3 s in the stand the
      // calibration is found in).
      const trackers::Stillness still = still_;
      const std::array<pose::FootLock, 2> locks{lock_[0], lock_[1]};
      const bool restart = !features::refines_size(k);
      if (restart) {
        reset_state();
      } else {
        feat_.reset();
        // The first calibration (after the default body, sized to the headset) replaces the
        // uncalibrated orientation offsets, so the GRU's state described other inputs: it starts
        // again, the feet stay locked (offdist csv 5.65 -> 5.52 cm; restarting the locks as well
        // gave 0.1-0.3 cm lower MPJPE but moved the standing feet: 2.3-2.9 cm/s).
        if (first && auto_.report().status == features::CalibrationStatus::Calibrated) net_.reset();
        lock_[0].rescale(k);
        lock_[1].rescale(k);
      }
      still_ = still;
      still_.rebase();  // the headset's calibrated pose jumps with the new offsets
      still_.assume_still();
      // A restart while the user stands (the calibrator's window): the feet stay where they were
      // shown, locked, instead of snapping to the restarted network's first stance.
      if (restart && cfg_.hold_feet_when_still && cfg_.contact_ik && still_.still()) {
        for (int i = 0; i < 2; ++i) {
          lock_[i] = locks[i];
          lock_[i].lock_in_place(k, &meta_.toe_height);  // and its last shown orientation
        }
      }
    }
    calib_.apply(s.pose, cal_);
    for (int k = 1; k <= 2; ++k) measured_[k - 1] = s.measured[k];
    still_.update(cal_[0].position, cal_[0].orientation, 1.0 / meta_.frame_rate);
    // A stand-up: the state from seated or crouched input, and the feet held there, are stale.
    if (stand_up_.update(s.pose[0].position, still_.still(), 1.0 / meta_.frame_rate)) reset_state();
    feat_.compute(cal_, x_);
    return x_;
  }
  SPARSEBODY_ONE_COPY void end_step(const T* y) noexcept {
    for (int i = 0; i < Net::out_size; ++i) y_[i] = y[i];
    decode_lower_body();
    if (cfg_.upper_body_ik) upper_.solve(body_, cal_, out_.pose(), out_.world());
    pose::forward_kinematics(body_, out_.pose(), out_.world());
    // the shoulders follow the trackers only with the upper body's IK
    if (cfg_.upper_body_ik && fit_arms()) {  // lengthened: this frame's arms solved again on them
      upper_.solve(body_, cal_, out_.pose(), out_.world());
      pose::forward_kinematics(body_, out_.pose(), out_.world());
    }
    contacts_and_legs();
    // The last-good guard, new with the shared front end (LoBSTr had none): a frame that would not
    // be finite keeps the last pose and restarts the GRU (a NaN would poison its state), as direct
    // mode does. A run without such a frame is unchanged.
    if (!out_.commit()) reset_state();
  }

  // Back to the constructed state; an explicit calibration is kept, an automatic one is
  // forgotten (the search starts again, as in a new instance).
  void reset() noexcept {
    if (!auto_.manual()) {
      auto_.recalibrate();
      calib_ = auto_.calibration();
    }
    reach_.reset(arm_start());
    fit_body();
    auto_.break_window();
    stand_up_.reset();
    reset_state();
    this->reset_front_end();
  }

  // --- results ------------------------------------------------------------------------------
  // pose(), world(), has_output(), frames() (PipelineFrontEnd): the pose on skeleton() in the
  // standard skeleton's scale (metres); multiply positions and offsets by user_scale() for the
  // user's size. skeleton(): the standard skeleton in the user's proportions (body_proportions();
  // the standard one until a calibration measures them: its offsets change at calibration, in
  // place); standard_skeleton(): the one the network was trained on.
  double user_scale() const noexcept { return 1.0 / calib_.scale; }
  const pose::Skeleton& skeleton() const noexcept { return body_; }
  const pose::Skeleton& standard_skeleton() const noexcept { return meta_.skeleton; }
  const pose::BodyProportions& body_proportions() const noexcept { return prop_; }
  const pose::JointMap& joint_map() const noexcept { return map_; }
  const predict::LoBSTrMeta& meta() const noexcept { return meta_; }
  const T* features() const noexcept { return x_; }
  nn::Network<Net>& network() noexcept { return net_; }
  const T* network_output() const noexcept { return y_; }  // [48 pose 6D | 2 left | 2 right]
  double contact_probability(int foot) const noexcept { return y_[48 + 2 * foot + 1]; }
  bool contact(int foot) const noexcept { return contact_probability(foot) > cfg_.contact_threshold; }
  bool foot_locked(int foot) const noexcept { return lock_[foot].state() != pose::FootLock::State::Free; }
  bool standing_still() const noexcept { return still_.still(); }
  // Stand-ups found (trackers/stand_up.hpp): each restarted the network and the foot locks.
  long long stand_ups() const noexcept { return stand_up_.count(); }
  int window() const noexcept { return window_; }
  RunMode mode() const noexcept { return cfg_.mode; }

 private:
  using Base::frames_;
  using Base::out_;
  using Base::stream_;

  // The output skeleton's proportions from the calibration in use: legs r = H_user / H_hips (the
  // pelvis tracker's standing hips height over the standard one, both in the standard scale),
  // torso t keeping the standing head height; the hips are lifted by H_user - H_hips above the
  // network's (standard) pelvis. Without a measured hips height: the standard skeleton.
  void fit_body() noexcept {
    prop_ = {};
    hips_lift_ = 0;
    const double H = meta_.standing_hips_height;
    if (explicit_body_) {
      prop_ = explicit_prop_;
    } else if (cfg_.fit_legs && calib_.hips_height > 0 && H > 0 && std::isfinite(calib_.hips_height)) {
      prop_.leg = std::clamp(calib_.hips_height / H, 1.0 - cfg_.leg_ratio_limit, 1.0 + cfg_.leg_ratio_limit);
      prop_.torso = pose::BodyProportions::torso_for_legs(prop_.leg, H, meta_.standing_head_height);
      hips_lift_ = (prop_.leg - 1.0) * H;
    }
    prop_.arm = reach_.ratio();  // from arm_start(), lengthened where the controllers showed more
    pose::apply_proportions(meta_.skeleton, map_, prop_, body_);
  }
  double arm_start() const noexcept { return explicit_body_ ? explicit_prop_.arm : 1.0; }

  // The controllers' distance from the shoulders this frame against the standard arm; true when
  // ArmReach lengthened the arms (body_ re-proportioned).
  bool fit_arms() noexcept {
    double e[2];
    for (int side = 0; side < 2; ++side)
      e[side] = pose::ArmReach::stretch(measured_[side], cal_[1 + side].position, out_.world().position[upper_.shoulder(side)], arm_length_[side]);
    if (!reach_.update(e[0], e[1], 1.0 / meta_.frame_rate)) return false;
    fit_body();
    return true;
  }

  void reset_state() noexcept {
    net_.reset();
    feat_.reset();
    lock_[0].reset();
    lock_[1].reset();
    still_.reset();
    filled_ = 0;
    head_ = 0;
  }

  const T* run_network() noexcept {
    if (cfg_.mode == RunMode::Streaming) return net_.step(x_);
    // Window: append x to the ring, then replay the last N frames from a zero state.
    std::copy(x_, x_ + kFeatures, ring_.data() + static_cast<std::size_t>(head_) * kFeatures);
    head_ = (head_ + 1) % window_;
    if (filled_ < window_) ++filled_;
    net_.reset();
    const T* y = nullptr;
    const int start = (head_ - filled_ + window_) % window_;
    for (int i = 0; i < filled_; ++i) y = net_.step(ring_.data() + static_cast<std::size_t>((start + i) % window_) * kFeatures);
    return y;
  }

  // Hips from the pelvis tracker (W_hips = P F_hips^T, p_hips = p_pelvis); the 8 lower-body joints
  // from the network's 6D output.
  void decode_lower_body() noexcept {
    const trackers::PoseD& pel = cal_[3];
    out_.pose().root_position = pel.position;
    // the user's hips: where the tracker's joint is, not at the standard height the network saw
    // (the calibration moved it along the calibrated pelvis's up axis)
    out_.pose().root_position += pel.orientation * Eigen::Vector3d(0, hips_lift_, 0);
    out_.pose().local[0] = Eigen::Quaterniond(pel.orientation.toRotationMatrix() * F_hips_T_).normalized();
    for (int i = 0; i < 8; ++i) out_.pose().local[meta_.lower[i]] = Eigen::Quaterniond(pose::from6d(y_ + 6 * i));
  }

  // Contacts from the network, foot locks, and leg IK keeping each foot's world orientation.
  void contacts_and_legs() noexcept {
    if (!cfg_.contact_ik) return;
    const pose::Skeleton& s = body_;
    bool changed = false;
    for (int foot = 0; foot < 2; ++foot) {
      const int* L = meta_.lower + 4 * foot;  // upper leg, lower leg, foot, toes
      const int ul = L[0], ll = L[1], ft = L[2], toe = L[3];
      const Eigen::Vector3d hip = out_.world().position[ul];
      const double leg = s.offsets[ll].norm() + s.offsets[ft].norm();  // hip to ankle, straight
      const double reach = 1.02 * leg + s.offsets[toe].norm();
      Eigen::Vector3d target;
      const bool still = cfg_.hold_feet_when_still && still_.still() && stand_up_.holding();
      lock_[foot].hold(still);
      // The user just stopped: the foot stays as shown last frame (the network walks on for a step).
      if (still && still_.stopped_now()) lock_[foot].stop(&meta_.toe_height);
      const bool in_contact = contact(foot) || (still && contact_probability(foot) > cfg_.still_contact_threshold);
      if (!lock_[foot].update(in_contact, out_.world().position[toe], hip, reach, cfg_.lock_max_drift, meta_.toe_height, target))
        continue;
      // While the user stands a locked foot keeps the orientation it was planted with (the
      // network may still roll it heel-up for a step it will not take), eased over 10 frames.
      Eigen::Quaterniond& foot_w = out_.world().rotation[ft];
      lock_[foot].orient(foot_w, still);
      if (cfg_.max_foot_roll > 0)
        foot_w = pose::roll_foot_into_reach(foot_w, target, s.offsets[toe], hip, leg, cfg_.max_foot_roll);
      // ankle target keeps the foot's world orientation: ankle = target - (toe - ankle)
      const Eigen::Vector3d ankle_t = target - foot_w * s.offsets[toe];
      const pose::WorldPose& w = out_.world();
      const Eigen::Vector3d &a = w.position[ul], &b = w.position[ll], &c = w.position[ft];
      const Eigen::Vector3d fwd = cal_[3].orientation.toRotationMatrix().col(2);
      // knee: in the leg's current bend plane, nudged forwards so a straight leg bends forwards
      const Eigen::Vector3d pole = (b - a) - (b - a).dot((c - a).normalized()) * (c - a).normalized() + 0.05 * fwd;
      const auto ik = pose::limb_to(a, b, c, w.rotation[ul], w.rotation[ll], ankle_t, pole, pose::LimbRotation::sequential());
      pose::set_limb_locals(out_.pose(), L, &w.rotation[s.parents[ul]], ik.upper, ik.lower, w.rotation[ft], true);
      changed = true;
    }
    if (changed) pose::forward_kinematics(s, out_.pose(), out_.world());
    for (int foot = 0; foot < 2; ++foot) lock_[foot].show(out_.world().rotation[meta_.lower[4 * foot + 2]]);
  }

  LoBSTrConfig cfg_;
  predict::LoBSTrMeta meta_;
  pose::Skeleton body_;            // meta_.skeleton in the user's proportions (prop_)
  pose::BodyProportions prop_{};
  pose::BodyProportions explicit_prop_{};  // set_body_proportions
  bool explicit_body_ = false;
  double hips_lift_ = 0;           // m, standard scale: the user's standing hips above the standard's
  pose::ArmReach reach_;
  double arm_length_[2] = {1, 1};  // standard upper arm + forearm
  bool measured_[2] = {};          // the controllers measured this frame (not held)
  nn::Network<Net> net_;
  features::Calibration calib_;
  features::AutoCalibration auto_;
  features::LoBSTrFeatures feat_;
  pose::JointMap map_{};
  Eigen::Matrix3d F_hips_T_;
  std::array<trackers::PoseD, trackers::kTrackerCount> cal_{};
  T x_[kFeatures] = {};
  T y_[Net::out_size] = {};
  pose::FootLock lock_[2];  // the toes' locks (10-frame blends), with the held feet's orientation
  trackers::Stillness still_;
  trackers::StandUp stand_up_;
  std::vector<T> ring_;
  int window_ = 30, filled_ = 0, head_ = 0;
  LoBSTrUpperBody upper_;
};

// The shipped configurations, by name: compact (H = 256, latent 128: examples/weights/
// lobstr_compact.weights.json) and the paper's size (H = 1024, latent 128), each with float, f16
// (half the weight bytes) or int8 (a quarter) weight storage.
using LoBSTrCompact = LoBSTrPipeline<float, 256, 128>;
using LoBSTrCompactF16 = LoBSTrPipeline<float, 256, 128, nn::f16>;
using LoBSTrCompactQ8 = LoBSTrPipeline<float, 256, 128, nn::q8>;
using LoBSTrPaper = LoBSTrPipeline<float, 1024, 128>;
using LoBSTrPaperF16 = LoBSTrPipeline<float, 1024, 128, nn::f16>;
using LoBSTrPaperQ8 = LoBSTrPipeline<float, 1024, 128, nn::q8>;

}  // namespace sparsebody::avatar
