// The Neural3Points avatar pipeline in direct mode (Ye et al., SCA 2022, §3, §4, §7): headset + two
// controllers in, a full-body pose on the standard skeleton out, no pelvis tracker needed.
//
//   TrackerFrame (any rate) -> Resampler (30 Hz) -> TrackerSanitizer (bad input)
//     -> N3PCalibration (device -> head / wrist joints, height scale, §7; found automatically from
//        standing windows by default, features/auto_calibration.hpp)
//     -> N3PPredictor (Eq. (2): G_sig -> G_lo -> heading update -> G_up; o* for missing controllers)
//     -> the body under the headset (ours, not the paper's): moved horizontally towards it (head
//        anchor), the spine bent to reach it (head reach), then moved vertically by what is left
//        (head height: crouching, kneeling, stepping up, jumping)
//     -> direct-mode IK (§7, "to enforce foot contacts and achieve accurate tracker positions"):
//        feet in contact (c > threshold) are pinned at the ankle (pose::FootLock, below) with
//        two-bone leg IK;
//        hands are put on the measured controllers with two-bone arm IK.
//
// Tracker modes, per frame from the validity flags (§8.2): 3-point; one controller (the missing one
// from o*); HMD only (both from o*). A controller that was never seen is predicted too. The pelvis
// tracker, if any, is ignored (use the LoBSTr pipeline for it).
// Bad input:
//   headset (trackers/sanitizer.hpp, as the LoBSTr pipeline): NaN / Inf / non-unit quaternion or a
//     jump makes it invalid for the frame and its last pose is held; a long loss, a tracking-origin
//     jump or a resampler gap (time jump) restarts the predictor from its default state; before the
//     first valid headset frame there is no output;
//   controllers: invalid flag, NaN / Inf, a quaternion off unit length by more than the sanitizer's
//     tolerance, or a position further than `controller_max_distance` from the headset: the
//     controller is missing for that frame and o* stands in (§8.2). No hold and no reset, so a
//     controller coming back after a long absence is simply used again.
// Calibration (as the LoBSTr pipeline): automatic by default; until a standing window is found the
// default body (s = 1, half-turn offsets, Config::devices' offsets), said by calibration_report();
// a new calibration restarts the predictor (no velocity spike). calibrate(frame) and
// set_calibration(c) are explicit and stop the search until recalibrate().
// The output pose is always finite: a frame that would not be keeps the last pose.
// Per frame: no allocation, no exception, no lock. Everything is sized at construction.
//
// Use (the LoBSTr pipeline's shape; N3PDirect is the shipped weights' configuration):
//   auto w = avatar::N3PDirect::load("examples/weights/n3p");   // n3p_{signal,lower,upper}.json
//   avatar::N3PDirect p(w);
//   // calibration is automatic (the first second of standing still); p.calibrate(frame) forces a
//   // frame (a T-pose measures the wrist offsets, §7), p.recalibrate() searches again
//   for (frame : frames) { p.push(frame); if (p.has_output()) use(p.pose(), p.world(), p.user_scale()); }
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

#include "sparsebody/avatar/pipeline_front_end.hpp"
#include "sparsebody/core/one_copy.hpp"
#include "sparsebody/features/auto_calibration.hpp"
#include "sparsebody/features/device_model.hpp"
#include "sparsebody/features/n3p_calibration.hpp"
#include "sparsebody/nn/half.hpp"
#include "sparsebody/nn/int8.hpp"
#include "sparsebody/pose/arm_reach.hpp"
#include "sparsebody/pose/body_pose.hpp"
#include "sparsebody/pose/body_proportions.hpp"
#include "sparsebody/pose/chain_reach.hpp"
#include "sparsebody/pose/contact.hpp"
#include "sparsebody/pose/foot_roll.hpp"
#include "sparsebody/pose/ik.hpp"
#include "sparsebody/pose/joint_map.hpp"
#include "sparsebody/predict/n3p_predictor.hpp"
#include "sparsebody/trackers/stand_up.hpp"
#include "sparsebody/trackers/stillness.hpp"

namespace sparsebody::avatar {

struct N3PConfig {
  double contact_threshold = 0.5;  // c above which a foot is in contact
  bool foot_ik = true;             // pin feet in contact (direct mode)
  bool hand_ik = true;             // hands on the measured controllers (direct mode)
  // The output skeleton's arms lengthened where the controllers are seen beyond their reach
  // (pose/arm_reach.hpp; skeleton() is then the standard one with longer arms).
  pose::ArmReachConfig arm_reach{};
  bool use_controllers = true;     // false: HMD-only mode even when controllers are tracked
  double controller_max_distance = 1.5;  // from the headset (m, user's size); further: missing
  double foot_max_drift = 0.3;     // a pinned foot further than this from the prediction is released (m)
  // Which point of a foot in contact is pinned. Toe (the default): the toe base, the ankle following
  // the predicted foot's rotation about it (as LoBSTr's lock). Ankle: the paper's §7 pin. The
  // contact labels the predictor learned are the toes' (toe base near the floor and slow), so a foot
  // stays in contact through its heel-off, when the ankle rises and moves forwards over the toes:
  // an ankle pin waits for the release, whose 8-frame blend then moves the toes at ~0.8 m/s while
  // the real ones are still down. offdist (every 5th validation clip), ankle -> toe: foot skating
  // nominal 13.4 -> 10.0 cm/s, device session 8.8 -> 6.8, csv 9.9 -> 8.2; feet while still 0.23 ->
  // 0.02 / 0.42 -> 0.09 / 0.94 -> 0.79 cm/s; MPJPE 4.50 -> 4.66 / 6.40 -> 6.45 / 6.21 -> 6.31 cm.
  // The physics mode's reference keeps the ankle pin (n3p_physics_config.hpp).
  enum class Pin { Ankle, Toe } pin = Pin::Toe;
  // While the user stands still, a toe-pinned foot whose ankle the leg cannot reach turns about the
  // toe (pose/foot_roll.hpp: the heel rises as the hips settle after a stop) by up to this much
  // (rad, ~57 deg) before the pin slides or is released. Not while moving: there a pin out of
  // reach is a step or a jump (head_height's release) and is let go.
  double max_foot_roll = 1.0;
  // ... and a held foot whose heel is up (a stop caught the rear foot at its push-off: toe pinned,
  // ankle 74-80 deg above it where a standing foot's is ~44, g_lo^0's) comes down towards the
  // standing elevation at this rate (rad/s), the roll above raising it as far as the leg needs.
  // Without it the avatar stood on the ball of its rear foot for the whole stand.
  double heel_settle_speed = 1.0;
  // Toe pins: while the headset rises or falls faster than this (m/s, standard scale, over 2 frames:
  // a jump's take-off, not a run's bob; 0.6 m/s fired at the csv sessions' dead stops and their
  // feet while still went 0.79 -> 1.26 cm/s) and for airborne_seconds after, feet are not held as
  // standing still (see pin_feet).
  double airborne_speed = 1.2;
  double airborne_seconds = 0.3;
  // While the user stands still (trackers::Stillness on the headset) pinned feet stay pinned and a
  // foot the predictor gives at least still_contact_threshold pins too: no creeping feet.
  bool hold_feet_when_still = true;
  double still_contact_threshold = 0.25;
  // ... and a foot released while walking (held off until its contact goes off once) locks again
  // once the network moves it slower than this (m/s; a foot it moves faster steps while the head
  // stays: it stays free). offdist, every 5th clip: feet while still 0.96 -> 0.22 cm/s (LoBSTr
  // nominal), 4.74 -> 3.21 (csv); without the speed limit 0.20 / 2.82 but +0.12 cm nominal MPJPE.
  double still_rearm_speed = 0.12;
  trackers::StillnessConfig stillness{};
  // A stand-up (the head back near its standing height after sitting or crouching) restarts the
  // predictor and lets go of the foot pins (trackers/stand_up.hpp).
  trackers::StandUpConfig stand_up{};
  // Head anchor: after every step the predicted body (its heading frame h) moves horizontally so
  // that its head joint is where the calibrated headset puts it. The predictor only integrates its
  // own dh, so without this the avatar drifts from the user (tens of cm in turns, metres over a
  // session). Vertical errors are left to the pose (moving the root would lift the feet).
  bool anchor_head = true;
  // Fraction of the horizontal head error removed per step (30 Hz: a time constant of ~0.1 s). On
  // 11 validation clips (offdist --every 30): gain 0 / 0.1 / 0.3 / 1 give MPJPE 4.78 / 4.69 / 4.59 /
  // 6.16 cm and head error 3.94 / 3.58 / 3.11 / 2.35 cm; 1 moves the free feet with every correction.
  double anchor_gain = 0.3;
  // At most this far per step (m, standard scale: 0.9 m/s at 30 Hz): a large error (a lost or jumped
  // headset) is left to the sanitizer's reset instead of dragging the body (and the physics mode's
  // reference) across the room in a few frames.
  double anchor_max_step = 0.03;
  // Head reach: then the spine (spine, chest, neck) bends so that the head joint reaches the
  // calibrated headset (pose::ChainReach, at most ~30 deg per joint), the head keeping its
  // orientation: what the anchor leaves (the height in a bow, a crouch, a restart) is not left in
  // the avatar's head. Before the hands' IK, so the arms follow the chest.
  bool head_reach = true;
  pose::ChainReachConfig spine{};
  // Head height: the vertical head error the spine's reach leaves, beyond a dead band, moves the
  // whole body. The predictor keeps its hips about 1 m up whatever the headset does: on the CMU
  // clips a climb left the head 40-50 cm below the headset and a kneel 40 cm above it.
  // - Down (a crouch, kneeling, sitting on the floor): the ankles stay where they were and the
  //   legs bend.
  // - Up (a jump, a step up, tiptoes): only as far as the pinned feet's legs reach; a headset
  //   more than `head_height_release` above that lifts them off. Lifting them at any excess
  //   released the pins of standing performers whose head was 5-9 cm above the predicted one,
  //   and their feet slid.
  // Output only: the predictor's state is untouched. Off in physics mode's reference.
  bool head_height = true;
  // m, standard scale: a smaller error is left to the pose. offdist (every 5th clip): 3 / 2 / 1 cm
  // give MPJPE nominal 4.52 / 4.50 / 4.42 cm, devices 6.41 / 6.39 / 6.37, CMU head error 3.20 / 2.75 /
  // 2.26 cm, but 1 cm moves the standing feet of csv sessions 0.94 -> 1.06 cm/s.
  double head_height_band = 0.02;
  double head_height_release = 0.15;  // m beyond the pinned legs' reach: a jump or a step up
  // ... or at once, while the headset rises faster than this (m/s, standard scale, over the last 2
  // frames): a jump's take-off (a 25 cm jump: ~1.7 m/s) rather than tiptoes or a stretch. Without
  // it that jump left the head up to 19 cm below the headset for its first 0.15 s. 0.8 m/s fired
  // on validation device sessions (feet while still 0.42 -> 0.46 cm/s); 1.2 never does.
  double head_height_jump_speed = 1.2;
  double head_height_max_step = 0.15; // m per step (4.5 m/s at 30 Hz); more catches up over frames
  // While the user stands still, held feet pinned more than `platform_height` above the standing
  // foot's height (m, standard scale: on a step, a ramp, a platform) rise with the head by at most
  // `platform_rise_step` a frame when their legs keep it below the headset. A walk up a ramp ends
  // with feet pinned where the last steps were made, lower than the platform, and the lift stopped
  // at their reach (the head 10 cm below the headset). Feet on the floor (the floor at y = 0)
  // never rise: there a head above the predicted one is the pose's, not a step's.
  double platform_height = 0.05;
  double platform_rise_step = 0.01;  // m per frame (0.3 m/s at 30 Hz)
  trackers::SanitizerConfig sanitizer{};
  features::DeviceModel devices{};                // device -> joint offsets (DeviceModel::none(): trackers at the joints)
  features::AutoCalibrationConfig calibration{};  // the standing-window search (enabled by default)
};

template <typename T = float, int HSig = 64, int HLo = 128, int HUp = 128, typename W = T>
class N3PPipeline : public PipelineFrontEnd<N3PPipeline<T, HSig, HLo, HUp, W>> {
  using Base = PipelineFrontEnd<N3PPipeline>;

 public:
  using Predictor = predict::N3PPredictor<T, HSig, HLo, HUp, W>;
  using Weights = typename Predictor::Weights;
  static constexpr int kHiddenSignal = HSig, kHiddenLower = HLo, kHiddenUpper = HUp;

  // prefix ("…/n3p") or any of the three files; throws LoadError.
  static Weights load(const std::string& path) { return Predictor::load(path); }

  explicit N3PPipeline(const Weights& w, N3PConfig cfg = {}) : cfg_(cfg), pred_(w) {
    const pose::Skeleton& s = pred_.skeleton();
    map_ = pose::JointMap::from_names(s, w.lo->info().source);
    this->start_front_end(pred_.meta().frame_rate, cfg.sanitizer, s.size());
    still_ = trackers::Stillness(cfg.stillness);
    stand_up_ = trackers::StandUp(cfg.stand_up);
    for (pose::FootLock& l : lock_) l.set_hold_rearm_step(cfg_.still_rearm_speed / pred_.meta().frame_rate);
    auto f = [&](const char* n) { return s.find(n); };
    const char* arm[2][3] = {{"UpperArm_L", "LowerArm_L", "Hand_L"}, {"UpperArm_R", "LowerArm_R", "Hand_R"}};
    const char* leg[2][3] = {{"UpperLeg_L", "LowerLeg_L", "Foot_L"}, {"UpperLeg_R", "LowerLeg_R", "Foot_R"}};
    for (int side = 0; side < 2; ++side)
      for (int i = 0; i < 3; ++i) {
        arm_[side][i] = f(arm[side][i]);
        leg_[side][i] = f(leg[side][i]);
        if (arm_[side][i] < 0 || leg_[side][i] < 0) throw LoadError("n3p pipeline", "skeleton lacks an arm or leg joint");
      }
    toe_[0] = f("Toes_L");
    toe_[1] = f("Toes_R");
    if (cfg_.pin == N3PConfig::Pin::Toe && (toe_[0] < 0 || toe_[1] < 0))
      throw LoadError("n3p pipeline", "skeleton lacks a toe joint (N3PConfig::pin = Toe)");
    for (int side = 0; side < 2; ++side)
      reach_[side] = s.offsets[leg_[side][1]].norm() + s.offsets[leg_[side][2]].norm();
    standing_feet();
    head_ = f("Head");
    spine_ = pose::ChainReach(pred_.skeleton(), head_, 3);
    body_ = s;  // the user's proportions are written into this copy (no allocation later)
    arm_reach_ = pose::ArmReach(cfg.arm_reach);
    for (int side = 0; side < 2; ++side) arm_length_[side] = pose::arm_length(s, arm_[side][2]);
    auto_ = features::AutoCalibration(cfg.devices, pred_.meta().standing_head_height, cfg.calibration);
    calib_.base = auto_.calibration();
    reset();
  }

  // --- calibration (§7) ---------------------------------------------------------------------
  // Explicit calibrations: used as given, the automatic search stops until recalibrate(). A change
  // restarts the predictor (as a reset does).
  void set_calibration(const features::n3p::N3PCalibration& c) noexcept {
    calib_ = c;
    auto_.set_explicit(c.base, features::CalibrationSource::Application);
    reset_state();
    ++calibration_changes_;
  }
  const features::n3p::N3PCalibration& calibration() const noexcept { return calib_; }
  // From a T-pose frame (wrist offsets measured when both controllers are where a T-pose puts
  // them) or any upright standing frame; false (unchanged) when the headset part cannot be used.
  bool calibrate(const trackers::TrackerFrame& frame) noexcept {
    features::n3p::N3PCalibration c;
    if (!c.from_tpose(frame, pred_.skeleton(), pred_.meta().standing_hips_height, pred_.meta().standing_head_height, cfg_.devices))
      return false;
    calib_ = c;
    auto_.set_explicit(c.base, features::CalibrationSource::Explicit, frame.time);
    reset_state();
    ++calibration_changes_;
    return true;
  }
  // The user's proportions when the application knows them (an avatar rig; the mocap skeleton that
  // drives trackers at the joints: pose::proportions_by_leg): only the arm ratio is used (see
  // fit_body), the arms seen beyond it still lengthen them, until recalibrate();
  // BodyProportions{} goes back to the standard ones. Ratios held within [0.75, 1.33].
  void set_body_proportions(const pose::BodyProportions& b) noexcept {
    explicit_prop_ = b.sane();
    explicit_body_ = !explicit_prop_.standard();
    fit_arms_reset();
  }
  // Forget the calibration (explicit or automatic) and search for standing windows again.
  void recalibrate() noexcept {
    auto_.recalibrate();
    calib_ = features::n3p::N3PCalibration{};
    calib_.base = auto_.calibration();
    explicit_body_ = false;
    fit_arms_reset();
    reset_state();
    ++calibration_changes_;
  }
  // What the calibration in use is based on (default body, automatic, explicit, refused).
  const features::CalibrationReport& calibration_report() const noexcept { return auto_.report(); }
  const features::AutoCalibration& auto_calibration() const noexcept { return auto_; }
  // For the front end (PipelineFrontEnd): the headset's o_head, and the controllers exchanged by
  // the tracker stream from the next tick on (their orientation offsets follow the devices; the
  // wrist offsets d_1, d_2 belong to the hands and stay).
  Eigen::Quaterniond head_offset() const noexcept { return calib_.base.offset[0]; }
  void swap_controller_calibration() noexcept {
    calib_.base.swap_controllers();
    auto_.swap_controllers();
  }
  // Counts calibration changes (automatic or explicit): a reader of this pipeline's output (the
  // physics mode) restarts when it moves.
  long long calibration_changes() const noexcept { return calibration_changes_; }

  // --- running ------------------------------------------------------------------------------
  // A caller that feeds step() its own ticks (the physics mode) and found a recentred tracking
  // space (trackers/recenter.hpp) says so before the next step: the sanitizer then takes the new
  // poses, as push() does, instead of holding them as a jump.
  void tracking_space_moved() noexcept { stream_.restart_sanitizer(); }

  // push(frame) (any rate, PipelineFrontEnd) runs step once per 30 Hz tick.
  // One model frame (the caller did the resampling). `restart`: state reset before this frame.
  void step(const trackers::TrackerFrame& f, bool restart = false) noexcept {
    if (!begin_step(f, restart)) return;
    auto& p = pred_;
    const T* x = p.after_signal(p.signal_network().step(p.begin_input()));
    x = p.after_lower(p.lower_network().step(x));
    end_step(p.finish(p.upper_network().step(x)));
  }

  // step() in two halves around the predictor's networks, for stepping many users together
  // (avatar/n3p_batch.hpp): begin_step does everything before G_sig and returns false when the
  // frame is done (no headset yet, or a frame the predictor cannot use); then the predictor's
  // phases run (predictor().begin_input() is G_sig's input; after_signal, after_lower, finish),
  // and end_step(finish's result) does the rest. Equal to step() bit for bit.
  SPARSEBODY_ONE_COPY bool begin_step(const trackers::TrackerFrame& f, bool restart = false) noexcept {
    trackers::TrackerFrame head_only = f;  // the sanitizer looks after the headset only
    head_only.valid[1] = head_only.valid[2] = head_only.valid[3] = false;
    const trackers::SanitizedFrame& s = stream_.sanitize(head_only);
    if (restart || s.reset) {
      reset_state();
      auto_.break_window();
    }
    ++frames_;
    if (!s.usable) return false;  // no headset yet: no output (or the last one is kept)
    std::array<trackers::PoseD, trackers::kTrackerCount> dev;
    std::array<bool, trackers::kTrackerCount> measured{s.measured[0], false, false, false};
    dev[0] = s.pose[0];
    for (int k = 1; k < 3; ++k) measured[k] = controller(f, k, s.pose[0].position, dev[k]);
    if (auto_.push(f.time, dev, measured)) {  // a new calibration found while running
      const double k = auto_.calibration().scale / calib_.base.scale;
      calib_ = features::n3p::N3PCalibration{};
      calib_.base = auto_.calibration();
      // A refinement (the size within 5 %): the predictor carries on in the rescaled world (its
      // heading frame's ground position x k; the body in that frame is in the standard scale
      // already) and the foot pins move with it, so the avatar does not jump. A larger change
      // restarts the predictor under the headset (its state described another body). Either way
      // the stillness detector (on the raw headset) carries on, and says still if the calibrator's
      // standing window is not over yet (as LoBSTr's).
      const trackers::Stillness still = still_;
      const std::array<pose::FootLock, 2> locks{lock_[0], lock_[1]};
      const bool restart = !features::refines_size(k);
      if (restart) {
        fit_arms_reset();  // arms measured at another size were measured on another body
        reset_state();
      } else {
        pred_.rescale_ground(k);
        lift_ *= k;
        headset_y_[0] *= k, headset_y_[1] *= k;  // heights in the standard scale
        lock_[0].rescale(k);
        lock_[1].rescale(k);
      }
      still_ = still;
      still_.assume_still();
      // A restart while the user stands (the calibrator's window): the feet stay pinned where they
      // were shown instead of snapping to the restarted predictor's first stance.
      if (restart && cfg_.hold_feet_when_still && cfg_.foot_ik && still_.still()) {
        for (int i = 0; i < 2; ++i) {
          lock_[i] = locks[i];
          lock_[i].lock_in_place(k);  // and its last shown orientation
        }
      }
      ++calibration_changes_;
    }
    features::n3p::TrackerSet o;
    std::array<bool, 3> present{true, false, false};  // the headset: measured or held
    o[0] = calib_.apply(0, s.pose[0]);
    still_.update(s.pose[0].position, s.pose[0].orientation, 1.0 / pred_.meta().frame_rate);
    // A stand-up: the predictor's state from seated or crouched input, and the feet pinned there,
    // are stale.
    if (stand_up_.update(s.pose[0].position, still_.still(), 1.0 / pred_.meta().frame_rate)) reset_state();
    for (int k = 1; k < 3; ++k) {
      present[k] = cfg_.use_controllers && measured[k];
      if (present[k]) o[k] = calib_.apply(k, dev[k]);
    }
    trackers_ = o;
    present_ = present;
    return pred_.begin(o, present) != nullptr;
  }
  SPARSEBODY_ONE_COPY void end_step(bool predicted) noexcept {
    if (!predicted) return;
    const features::n3p::TrackerSet& o = trackers_;
    const std::array<bool, 3>& present = present_;
    out_.pose() = pred_.pose();  // same size: no allocation
    pose::forward_kinematics(body_, out_.pose(), out_.world());
    if (cfg_.anchor_head && head_ >= 0) {
      const Eigen::Vector3d d = o[0].p - out_.world().position[head_];
      Eigen::Vector3d shift = cfg_.anchor_gain * Eigen::Vector3d(d.x(), 0.0, d.z());
      if (shift.norm() > cfg_.anchor_max_step) shift *= cfg_.anchor_max_step / shift.norm();
      if (!shift.allFinite()) shift.setZero();
      pred_.shift(shift.x(), shift.z());
      out_.pose().root_position += shift;
      for (auto& p : out_.world().position) p += shift;
    }
    if (cfg_.head_reach && !spine_.empty()) {
      spine_.solve(body_, out_.pose(), out_.world(), o[0].p, cfg_.spine);
      pose::forward_kinematics(body_, out_.pose(), out_.world());
    }
    track_headset_height(o[0].p.y());
    if (cfg_.head_height && head_ >= 0) follow_head_height(o[0].p.y());
    if (cfg_.foot_ik) pin_feet();
    if (cfg_.hand_ik) {
      fit_arms(o, present);
      for (int side = 0; side < 2; ++side)
        if (present[1 + side]) put_limb(arm_[side], o[1 + side].p);
    }
    if (cfg_.foot_ik || cfg_.hand_ik) pose::forward_kinematics(body_, out_.pose(), out_.world());
    if (!out_.commit()) reset_state();  // never hand out a NaN: the last pose is kept; restart
  }

  // Back to the constructed state; an explicit calibration is kept, an automatic one is
  // forgotten (the search starts again, as in a new instance).
  void reset() noexcept {
    if (!auto_.manual()) {
      auto_.recalibrate();
      calib_ = features::n3p::N3PCalibration{};
      calib_.base = auto_.calibration();
    }
    fit_arms_reset();
    auto_.break_window();
    stand_up_.reset();
    reset_state();
    this->reset_front_end();
  }

  // --- results ------------------------------------------------------------------------------
  // pose(), world(), has_output(), frames() (PipelineFrontEnd): the pose on the standard skeleton
  // in its scale (metres); multiply positions and offsets by user_scale() for the user's size.
  double user_scale() const noexcept { return 1.0 / calib_.base.scale; }
  // skeleton(): the output's, the standard skeleton with the user's arms (body_proportions(); the
  // offsets change in place when the arms are lengthened); standard_skeleton(): the network's.
  // The legs and torso stay standard: no tracker here shows them (LoBSTr's pelvis tracker does).
  const pose::Skeleton& skeleton() const noexcept { return body_; }
  const pose::Skeleton& standard_skeleton() const noexcept { return pred_.skeleton(); }
  const pose::BodyProportions& body_proportions() const noexcept { return prop_; }
  const pose::JointMap& joint_map() const noexcept { return map_; }
  const predict::N3PMeta& meta() const noexcept { return pred_.meta(); }
  const Predictor& predictor() const noexcept { return pred_; }
  Predictor& predictor() noexcept { return pred_; }  // for the phases of begin_step / end_step
  double contact_probability(int foot) const noexcept { return pred_.contact(foot); }
  bool contact(int foot) const noexcept { return contact_probability(foot) > cfg_.contact_threshold; }
  bool foot_locked(int foot) const noexcept { return lock_[foot].state() != pose::FootLock::State::Free; }
  bool standing_still() const noexcept { return still_.still(); }
  // Stand-ups found (trackers/stand_up.hpp): each restarted the predictor and the foot pins.
  long long stand_ups() const noexcept { return stand_up_.count(); }
  // Controllers replaced by o* in the last frame (0: 3-point, 1: one controller, 2: HMD only).
  int predicted_controllers() const noexcept { return pred_.substituted(1) + pred_.substituted(2); }
  // The calibrated trackers of the last usable frame (joint poses, standard-skeleton scale) and which
  // were measured (the others are stale); read by the physics mode's combined control predictor.
  const features::n3p::TrackerSet& trackers() const noexcept { return trackers_; }
  const std::array<bool, 3>& trackers_present() const noexcept { return present_; }
  const N3PConfig& config() const noexcept { return cfg_; }

 private:
  using Base::frames_;
  using Base::out_;
  using Base::stream_;

  // Arm length from controller reach (pose/arm_reach.hpp): the measured controllers' distance from
  // the shoulders against the standard arm; longer arms in body_ when ArmReach says so.
  void fit_arms(const features::n3p::TrackerSet& o, const std::array<bool, 3>& present) noexcept {
    double e[2];
    for (int side = 0; side < 2; ++side)
      e[side] = pose::ArmReach::stretch(present[1 + side], o[1 + side].p, out_.world().position[arm_[side][0]], arm_length_[side]);
    if (!arm_reach_.update(e[0], e[1], 1.0 / pred_.meta().frame_rate)) return;
    fit_body();
    pose::forward_kinematics(body_, out_.pose(), out_.world());  // this frame's IK on the new arms
  }
  void fit_arms_reset() noexcept {
    arm_reach_.reset(explicit_body_ ? explicit_prop_.arm : 1.0);  // from the application's arms, if any
    fit_body();
  }
  // body_ from the application's proportions (set_body_proportions) or the standard ones, with the
  // arms the reach has seen.
  void fit_body() noexcept {
    prop_ = explicit_body_ ? explicit_prop_ : pose::BodyProportions{};
    // Only the arms: the predictor places the body from the head with the standard torso and legs.
    // Given the CMU clips' torsos (x0.87-1.20), the head reach and height left the head 3.64 cm
    // from the headset instead of 2.70 (offdist cmu; MPJPE 19.59 -> 19.54 cm).
    prop_.leg = prop_.torso = 1.0;
    prop_.arm = arm_reach_.ratio();
    pose::apply_proportions(pred_.skeleton(), map_, prop_, body_);
  }

  void reset_state() noexcept {
    lift_ = 0.0;
    headset_y_[0] = headset_y_[1] = head_vy_ = std::numeric_limits<double>::quiet_NaN();
    pred_.reset();
    lock_[0].reset();
    lock_[1].reset();
    airborne_ = 0;
    still_.reset();
  }

  // Controller k of the raw frame when it is usable (see the bad-input rules above).
  bool controller(const trackers::TrackerFrame& f, int k, const Eigen::Vector3d& head, trackers::PoseD& out) const noexcept {
    trackers::PoseD p;  // the sanitizer's test of a pose (finite, |q| near 1, renormalised)
    if (!f.valid[k] || !trackers::checked_pose(f.pose[k], cfg_.sanitizer.quat_tolerance, p)) return false;
    if (!((p.position - head).norm() <= cfg_.controller_max_distance)) return false;
    out = p;
    return true;
  }

  // N3PConfig::head_height: the body moves vertically by the head error beyond the dead band.
  // Going down, each ankle is put back where it was (the legs bend; an ankle the lowered hip
  // cannot reach stretches towards it); going up, the feet go with the body and pin_feet()
  // stretches the legs to their pins or releases them.
  // The headset's vertical speed over the last two frames (head_vy_, m/s, standard scale; NaN until
  // there are two), which head height (a jump's take-off) and toe pins (airborne) both read.
  void track_headset_height(double headset_y) noexcept {
    head_vy_ = (headset_y - headset_y_[1]) * pred_.meta().frame_rate / 2;
    headset_y_[1] = headset_y_[0];
    headset_y_[0] = headset_y;
  }

  void follow_head_height(double headset_y) noexcept {
    const double e = headset_y - out_.world().position[head_].y();
    const double band = cfg_.head_height_band;
    double want = !std::isfinite(e) ? 0.0 : e > band ? e - band : e < -band ? e + band : 0.0;
    if (want > 0.0 && !(head_vy_ > cfg_.head_height_jump_speed)) {
      // up: as far as the pinned legs reach; a head higher by `release` lifts them (a jump's
      // take-off lifts them at once)
      double m = pinned_lift();
      if (want > m) m += raise_platform_pins(want - m);  // a pin raised by dy lets the body rise dy more
      want = std::min(want, m) + std::max(0.0, want - m - cfg_.head_height_release);
    }
    // the lift changes by at most max_step a frame (the pose under it is the network's each frame)
    const double dy = std::clamp(want, lift_ - cfg_.head_height_max_step, lift_ + cfg_.head_height_max_step);
    lift_ = dy;
    if (dy == 0.0) return;
    Eigen::Vector3d ankle[2];
    for (int side = 0; side < 2; ++side) ankle[side] = out_.world().position[leg_[side][2]];
    out_.pose().root_position.y() += dy;
    for (auto& p : out_.world().position) p.y() += dy;
    if (dy > 0.0) return;
    for (int side = 0; side < 2; ++side) put_limb(leg_[side], ankle[side]);
    pose::forward_kinematics(body_, out_.pose(), out_.world());
  }

  // How far the body can rise with every pinned ankle within 98 % of its leg's reach (+inf: none
  // pinned). At 100 % rounding released the pin a frame later, and the foot slid as it blended
  // to the network's (offdist devices, standing clips: foot skating 0.7 -> 4-10 cm/s).
  double pinned_lift() const noexcept {
    double m = std::numeric_limits<double>::infinity();
    for (int side = 0; side < 2; ++side) {
      if (lock_[side].state() != pose::FootLock::State::Locked) continue;
      const Eigen::Vector3d d = out_.world().position[leg_[side][0]] - ankle_pin(side);  // hip - pin
      const double r = 0.98 * reach_[side], h2 = d.x() * d.x() + d.z() * d.z();
      m = std::min(m, h2 < r * r ? std::max(0.0, std::sqrt(r * r - h2) - d.y()) : 0.0);
    }
    return m;
  }

  // Feet in contact stay where contact began (lock_), the leg bent to reach them. While the user
  // stands still a locked foot also keeps the orientation it was planted with (the lock holds the
  // ankle, so a foot turning about it moves the toes: 1.2 cm/s of creep), eased in and out over
  // 8 frames.
  void pin_feet() noexcept {
    const bool toe_pin = cfg_.pin == N3PConfig::Pin::Toe;
    // Toe pins: the headset moving up or down fast (a jump, a drop) holds nothing for a while. The
    // stillness detector watches horizontal motion only, so a jump from a stand is "still", and a
    // held toe re-pinned at the top of the jump (where the network, lifted with the body, moves
    // its foot slowly) stayed there after the landing.
    if (std::abs(head_vy_) > cfg_.airborne_speed) airborne_ = static_cast<int>(std::lround(cfg_.airborne_seconds * pred_.meta().frame_rate));
    else if (airborne_ > 0) --airborne_;
    for (int side = 0; side < 2; ++side) {
      const int* l = leg_[side];
      Eigen::Vector3d target;
      const bool still = cfg_.hold_feet_when_still && still_.still() && !(toe_pin && airborne_ > 0) && stand_up_.holding();
      lock_[side].hold(still);
      const bool c = contact(side) || (still && contact_probability(side) > cfg_.still_contact_threshold);
      // The user just stopped: the foot stays as shown last frame (the network walks on for a step).
      if (still && still_.stopped_now()) lock_[side].stop();
      pose::WorldPose& w = out_.world();
      Eigen::Quaterniond& foot_w = w.rotation[l[2]];
      const Eigen::Vector3d& hip = w.position[l[0]];
      Eigen::Vector3d lock_hip = hip;
      const Eigen::Vector3d& t = body_.offsets[toe_pin ? toe_[side] : l[2]];  // the toe in the foot frame (toe pins)
      if (toe_pin) {
        // A toe pin is in reach when the ankle it asks for is: the lock measures it from the hip
        // moved by the foot's toe offset, the foot as it will be shown (a held foot keeps its
        // planted orientation, FootLock::orient: judged by the network's foot instead, a pin the
        // legs could not reach in a jump was kept, and the feet stayed in the air after landing).
        const Eigen::Quaterniond* last = lock_[side].shown_foot();
        Eigen::Quaterniond shown = still && last ? *last : foot_w;
        if (still && lock_[side].state() == pose::FootLock::State::Locked)
          shown = pose::roll_foot_into_reach(shown, lock_[side].lock_position(), t, hip, reach_[side], cfg_.max_foot_roll);
        lock_hip += shown * t;
      }
      if (lock_[side].update(c, w.position[toe_pin ? toe_[side] : l[2]], lock_hip, reach_[side], cfg_.foot_max_drift, target)) {
        lock_[side].orient(foot_w, still);  // planted while still, eased over 8 frames
        if (toe_pin && still && cfg_.heel_settle_speed > 0 && lock_[side].state() == pose::FootLock::State::Locked) {
          // a heel left up comes down as far as the leg reaches (the shown foot turns with the
          // planted one)
          const Eigen::Quaterniond& q = lock_[side].planted();
          const Eigen::Quaterniond low = pose::roll_foot_into_reach(
              pose::lower_heel(q, t, stand_elevation_[side], cfg_.heel_settle_speed / pred_.meta().frame_rate), target, t, hip,
              reach_[side], cfg_.max_foot_roll);
          if ((target - low * t - hip).norm() < reach_[side] && (low * t).y() > (q * t).y()) {  // in reach and lower
            const Eigen::Quaterniond dq = low * q.conjugate();
            lock_[side].turn_planted(dq);
            foot_w = (dq * foot_w).normalized();
          }
        }
        if (toe_pin) {  // the ankle, the foot turning about the toe
          if (still) foot_w = pose::roll_foot_into_reach(foot_w, target, t, hip, reach_[side], cfg_.max_foot_roll);
          target -= foot_w * t;
        }
        put_limb(l, target);
        pose::forward_kinematics(body_, out_.pose(), out_.world());
      }
      lock_[side].show(out_.world().rotation[l[2]]);
    }
  }
  // The standing foot from g_lo^0 (the predictor's first state, a standing pose in h^0): the pinned
  // joint's height and the ankle's elevation above the toe. A skeleton whose foot or toe is not in
  // J_lo has no such pose: both stay +inf, and the heel settle and the platform rise never act.
  void standing_feet() noexcept {
    const auto& m = pred_.meta();
    auto at = [&](int joint, Eigen::Vector3d& p) {
      for (int i = 0; i < features::n3p::kLowerJoints; ++i)
        if (joint >= 0 && m.lower[i] == joint) {
          p = Eigen::Vector3d(m.glo0.data() + features::n3p::LowerBlock::pos(i));
          return true;
        }
      return false;
    };
    for (int side = 0; side < 2; ++side) {
      stand_pin_y_[side] = stand_elevation_[side] = std::numeric_limits<double>::infinity();
      Eigen::Vector3d ankle, toe;
      const bool has_ankle = at(leg_[side][2], ankle), has_toe = at(toe_[side], toe);
      if (cfg_.pin == N3PConfig::Pin::Toe ? has_toe : has_ankle) stand_pin_y_[side] = (cfg_.pin == N3PConfig::Pin::Toe ? toe : ankle).y();
      if (has_ankle && has_toe) stand_elevation_[side] = pose::ankle_elevation(ankle - toe);
    }
  }

  // N3PConfig::platform_height: while the user stands still and every held foot is pinned above the
  // floor, the pins rise by up to `want` (at most platform_rise_step); returns how far.
  double raise_platform_pins(double want) noexcept {
    if (!(want > 0) || !cfg_.hold_feet_when_still || !still_.still() || airborne_ > 0) return 0.0;
    bool any = false;
    for (int side = 0; side < 2; ++side) {
      if (lock_[side].state() != pose::FootLock::State::Locked) continue;
      if (!(lock_[side].lock_position().y() > stand_pin_y_[side] + cfg_.platform_height)) return 0.0;
      any = true;
    }
    if (!any) return 0.0;
    const double dy = std::min(want, cfg_.platform_rise_step);
    for (auto& l : lock_)
      if (l.state() == pose::FootLock::State::Locked) l.raise(dy);
    return dy;
  }

  // Where a pinned foot's ankle is: the pin itself, or the toe pin less the foot's toe offset, the
  // foot as last shown (planted while the user stands; the network's foot may be heel-up).
  Eigen::Vector3d ankle_pin(int side) const noexcept {
    const Eigen::Vector3d& p = lock_[side].lock_position();
    if (cfg_.pin != N3PConfig::Pin::Toe) return p;
    const Eigen::Quaterniond* shown = lock_[side].shown_foot();
    const Eigen::Quaterniond& foot = shown ? *shown : out_.world().rotation[leg_[side][2]];
    return p - foot * body_.offsets[toe_[side]];
  }

  // Two-bone IK on the chain j[0] -> j[1] -> j[2] (pose::limb_to, bent in its current plane, the
  // end's world rotation kept, world rotations renormalised): the end goes to `target`. The world
  // pose is stale until the caller's forward kinematics.
  void put_limb(const int* j, const Eigen::Vector3d& target) noexcept {
    const pose::WorldPose& w = out_.world();
    const Eigen::Vector3d &pa = w.position[j[0]], &pb = w.position[j[1]], &pc = w.position[j[2]];
    const auto s = pose::limb_to(pa, pb, pc, w.rotation[j[0]], w.rotation[j[1]], target, pb - pa);
    const int parent = pred_.skeleton().parents[j[0]];
    pose::set_limb_locals(out_.pose(), j, parent < 0 ? nullptr : &w.rotation[parent], s.upper.normalized(),
                          s.lower.normalized(), w.rotation[j[2]], false);
  }

  N3PConfig cfg_;
  Predictor pred_;
  features::n3p::N3PCalibration calib_;
  features::AutoCalibration auto_;
  long long calibration_changes_ = 0;
  pose::JointMap map_;
  pose::Skeleton body_;  // the standard skeleton with the user's arms (prop_)
  pose::BodyProportions prop_{};
  pose::BodyProportions explicit_prop_{};  // set_body_proportions
  bool explicit_body_ = false;
  pose::ArmReach arm_reach_;
  double arm_length_[2] = {1, 1};  // standard upper arm + forearm
  // Direct-mode foot pinning (pose::FootLock): the ankle pinned where contact began (its own
  // height; a foot caught in the air by a stop is put down), released over 8 frames; a pin released
  // for distance needs the contact to go off on a later frame before it pins again.
  pose::FootLock lock_[2] = {pose::FootLock(8, pose::FootLock::Rearm::NextFrame),
                             pose::FootLock(8, pose::FootLock::Rearm::NextFrame)};
  trackers::Stillness still_;
  trackers::StandUp stand_up_;
  features::n3p::TrackerSet trackers_{};
  std::array<bool, 3> present_{};
  int arm_[2][3] = {}, leg_[2][3] = {};
  int toe_[2] = {-1, -1};
  int airborne_ = 0;  // frames left without the hold (toe pins after fast vertical head motion)
  int head_ = -1;
  pose::ChainReach spine_;
  double reach_[2] = {};
  double stand_pin_y_[2] = {};      // standing_feet(): the pinned joint's height (m, standard scale; +inf: unknown)
  double stand_elevation_[2] = {};  // ... and the ankle's elevation above the toe (rad; +inf: unknown)
  double lift_ = 0.0;  // the vertical offset follow_head_height() gave the last frame (m, standard scale)
  double headset_y_[2] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()};  // last 2 frames'
  double head_vy_ = std::numeric_limits<double>::quiet_NaN();  // track_headset_height
};

// The shipped configuration, by name: the paper's sizes (G_sig / G_lo / G_up hidden 64 / 128 / 128:
// examples/weights/n3p_*.json) with float, f16 (half the weight bytes) or int8 (a quarter) storage.
using N3PDirect = N3PPipeline<float, 64, 128, 128>;
using N3PDirectF16 = N3PPipeline<float, 64, 128, 128, nn::f16>;
using N3PDirectQ8 = N3PPipeline<float, 64, 128, 128, nn::q8>;

}  // namespace sparsebody::avatar
