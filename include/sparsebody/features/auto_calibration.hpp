// Automatic calibration: a real headset session starts with the user walking, not in a T-pose, so
// the calibration is taken from the moments the user stands still, found in the tracker stream.
// Fed the sanitised model-rate frames (poses, validity, time stamps), it finds standing windows:
//   >= min_window (1.0 s) of consecutive frames with the headset valid where the mean head speed
//   is < 0.08 m/s and every frame's < 0.25 m/s, the head height range < 3 cm, the headset upright
//   (its up axis has world y > 0.8) and not looking at the floor (|forward.y| < 0.5), and every
//   valid controller >= 0.2 m below the headset, within 0.7 m of it horizontally, with a mean
//   speed < 0.25 m/s.
// A window grows while the user stays still and is closed when the stillness ends or it reaches
// max_window (2.0 s; the rest of that stand is not used: one window per stand). From it:
//   - orientation offsets o_k = q_k^-1 Yaw(headset forward) at the window's stillest frame (head
//     plus controller speed smallest): the T-pose formula the networks were trained with (every
//     calibrated tracker has the body's facing frame), which needs an upright user facing
//     forward, not a T-pose. The headset's is the device model's (level_head): OpenXR gives its
//     tilt against gravity, and a user may look down at the controllers while standing;
//   - the eye height: the median over the window of the headset height the head would give
//     upright (the head joint's height, the eye offset turned with the headset, plus e.y; above the
//     floor);
//   - stature = eye height / 0.936: eye height is 0.936 of stature in Winter, "Biomechanics and
//     Motor Control of Human Movement", Fig. 4.1 (segment lengths after Drillis & Contini 1966);
//   - s = standard head-joint height / (eye height - e.y) (features/calibration.hpp).
// The first stand need not last min_window: after first_window (0.5 s) of it a provisional estimate
// is used (report.provisional), and the same window, closed when the stand ends or reaches
// max_window, replaces it (a refinement: the size barely changes, so the pipelines carry on).
// Waiting the whole first stand ran the default body for ~2 s, which on a 1.90 m user cost
// Neural3Points ~20 cm of head height for those seconds.
// A stature outside [1.2, 2.2] m is refused (counted, not used). Later windows refine: one whose
// eye height is > 4 cm above the estimate replaces it (the first was not fully upright), one
// within +-4 cm is averaged in (stature; the offsets of the estimate are kept) and raises the
// confidence, one > 4 cm lower (sitting, crouching) is skipped and counted.
// A controller's orientation offset is taken from a window only where the controller is held as a
// hand holds it at a stand: its offset within max_grip_deviation (45 deg) of the device model's
// (DeviceModel::default_orientation_offset: a relaxed hand, the nominal grip). A controller put down
// on a table while the user stands is ~90 deg off; so is one in a hand on a hip or raised to the
// chest. Such a controller keeps its offset (the device model's until a window gives a plausible
// one), and the first later window that does gives it, averaged in or not: an offset 90 deg wrong
// cost LoBSTr 1.3 cm and Neural3Points 1.8 cm MPJPE on validation sessions that start with the
// controllers on a table (the device model's offset: +0.1 cm). The report counts such windows
// (grips_not_held) and says which controller is still at the device model's.
// Confidence = mean window quality x (0.7 + 0.3 agreement): quality = 0.5 min(1, length /
// max_window) + 0.5 stillness (1 - 0.5 mean speed / 0.08 - 0.5 height range / 0.03); agreement =
// (1 - 1/n) (1 - spread / 4 cm) for n >= 2 averaged windows, else 0. So one window gives at most
// 0.7, agreeing windows approach 1.
// Before the first estimate the default body is used, but never one smaller than the headset
// shows (size_from_headset): at the first upright headset frame, if its eye height above the floor
// is above the default body's, the body is enlarged to that eye height (a lower bound on the
// stature: nobody's eyes are above their standing eye height; it is no calibration, and the status
// stays Default). A tall user's first stand then refines the size (within 5 %: the pipelines carry
// on) instead of changing it by 20 % (a restart that moved the feet of the 1.90 m bodies while they
// stood). A seated or short user keeps the default body until they stand.
// Floor: the reference space's y = 0 (OpenXR STAGE). estimate_floor, for apps whose floor is not
// reliable: the stature cannot be seen then, so it is assumed (assumed_stature, 1.70 m) and the
// floor is put 0.936 x 1.70 m below the accepted standing eye height; the report says so. The same
// happens by itself (until recalibrate()) when a standing window's eye height is below
// floor_fallback_eye (0.5 m): nobody stands with their eyes that low, so y = 0 is not the floor (an
// OpenXR LOCAL space has y = 0 at the head's starting height); before, that window was refused and
// the session ran the default body with its head at the floor.
// push() returns true when calibration() changed: the pipeline then restarts its feature
// history (like a reset), so the change gives no velocity spike. No allocation, no exception;
// NaN or invalid frames simply break a window.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>

#include "sparsebody/features/calibration.hpp"
#include "sparsebody/features/calibration_report.hpp"
#include "sparsebody/features/device_model.hpp"
#include "sparsebody/trackers/types.hpp"

namespace sparsebody::features {

struct AutoCalibrationConfig {
  bool enabled = true;                 // false: no search (the default body until calibrated explicitly)
  double min_window = 1.0;             // s of standing still for a window
  // s: while there is no estimate yet, a stand this long gives a first, provisional one (the
  // window stays open and replaces it when it closes), so a session does not run the default body
  // for the whole first stand. 0: off (the first estimate waits for min_window like the others).
  double first_window = 0.5;
  // ... and only a still one: stillness (below) at least this (a 1 s window needs none). The
  // jumping CMU clip 01_01's 0.5 s pause scores 0.49; a held stand with device noise ~0.9.
  double first_window_stillness = 0.6;
  double max_window = 2.0;             // s: a window is closed at this length
  double mean_head_speed = 0.08;       // m/s, window mean below
  double max_head_speed = 0.25;        // m/s, every frame below
  double head_height_range = 0.03;     // m, window range below
  double min_up_y = 0.8;               // headset up axis, world y above
  double max_forward_y = 0.5;          // |headset forward, world y| below
  double controller_below = 0.2;       // m: a valid controller at least this far below the headset
  double controller_horizontal = 0.7;  // m: and within this horizontally
  double controller_mean_speed = 0.25; // m/s, window mean below
  double max_frame_gap = 0.25;         // s between consecutive frames; longer breaks a window
  double eye_height_ratio = 0.936;     // eye height / stature (Winter, Fig. 4.1)
  double min_stature = 1.2, max_stature = 2.2;  // m: plausible; outside is refused
  double agreement = 0.04;             // m of eye height: same stand (average) / higher (replace) / lower (skip)
  bool estimate_floor = false;         // floor from the standing eye height (stature assumed)
  double assumed_stature = 1.70;       // m, with estimate_floor
  double floor_fallback_eye = 0.5;     // m: a standing eye height below this turns estimate_floor on (0: never)
  bool size_from_headset = true;       // the default body no smaller than the first upright headset frame shows (not with estimate_floor)
  // A bent stand: the headset of a walking user stays more than `rise_margin` above the automatic
  // estimate's eye height for `rise_time` s: the estimate is raised to the lowest height of that
  // run (see rise()). 0: off.
  double rise_margin = 0.04;            // m
  double rise_time = 0.3;               // s
  double rise_walk_speed = 0.3;         // m/s: horizontal headset speed of a frame that counts (walking)
  double rise_max_vertical_speed = 1.0; // m/s: faster up or down ends the run (a jump, sitting down)
  // ... and no larger either: the default body takes the first upright headset frame's stature
  // (within [min_stature, max_stature]) whether above or below the default's. For a simulated
  // avatar as tall as the user (QuestSim sizes its character from the headset, §3.6): a 1.75 m
  // body under a 1.55 m user's headset crouches; a kinematic pipeline keeps the lower bound only.
  bool size_from_headset_both_ways = false;
  // deg: a controller whose offset at a window is further than this from the device model's is not
  // held as at a stand (on a table, a hand on a hip): not taken from that window. 0: always taken.
  // The validation sessions' standing first frames, with each user's grip (up to 30 deg off),
  // give 0.5-33 deg.
  double max_grip_deviation = 45.0;
  // The head level when the headset is (OpenXR gives its tilt against gravity): the headset's
  // orientation offset is the device model's (DeviceModel::default_orientation_offset), not taken
  // from the window, and each window sample's eye height is the one its head would have upright
  // (head joint height, the eye offset turned with the headset, plus e.y). A user who looks down at
  // the controllers through the first stand (25 deg) otherwise calibrated a head 25 deg down for
  // the whole session (head error 2.5 -> 5.9 cm) and a body ~3 % short. Only with a device model's
  // eye offset (real headsets; not DeviceModel::none(), trackers at the joints).
  bool level_head = true;
  double level_head_min_tilt = 10.0;  // deg: ... when the headset tilts more than this at the window
};

class AutoCalibration {
 public:
  static constexpr int kCapacity = 256;  // frames held: 2 s up to 127 Hz (a full buffer closes the window)
  using Poses = std::array<trackers::PoseD, trackers::kTrackerCount>;
  using Flags = std::array<bool, trackers::kTrackerCount>;

  AutoCalibration() : AutoCalibration(DeviceModel{}, 1.38) {}
  // standard_head_height: the standard skeleton's standing head-joint height (the networks' meta).
  // standard_hips_height: its standing hips height, where a pelvis tracker is put at calibration
  // (DeviceModel::pelvis_from_standing; 0: the pelvis tracker keeps the device model's offset).
  AutoCalibration(const DeviceModel& devices, double standard_head_height, AutoCalibrationConfig cfg = {},
                  double standard_hips_height = 0) noexcept
      : cfg_(cfg), devices_(devices), eye_in_headset_(DeviceModel::default_orientation_offset() * devices.eye),
        standard_head_(standard_head_height), standard_hips_(standard_hips_height) {
    recalibrate();
  }

  // One model frame (after the sanitizer): poses and which were measured this frame. True when
  // calibration() changed.
  bool push(double time, const Poses& pose, const Flags& valid) noexcept {
    ++frame_;
    if (!searching()) return false;
    const bool sized = !sized_ && size_from_headset(pose, valid);
    // the headset's velocity from the previous frame, before search() remembers this one
    Eigen::Vector3d v;
    const bool vel = head_velocity(time, pose, valid, v);
    const bool found = search(time, pose, valid);
    if (!vel) rise_run_ = false;  // no velocity: not a walking frame, the run ends
    const bool raised = !found && vel && rise(time, pose, valid, v);
    return found || sized || raised;
  }

  // Forget everything (estimate, counters, an explicit calibration) and search again: after the
  // user sat down, or handed the headset on.
  void recalibrate() noexcept {
    manual_ = false;
    floor_fallback_ = false;
    est_n_ = 0;
    grip_set_.fill(false);
    provisional_ = prov_open_ = false;
    sized_ = false;
    early_next_ = -std::numeric_limits<double>::infinity();
    frame_ = 0;
    calib_ = Calibration::uncalibrated(devices_);
    report_ = CalibrationReport{};
    report_.stature = default_stature();
    report_.eye_height = default_stature() * cfg_.eye_height_ratio;
    std::snprintf(report_.message, sizeof report_.message, "%s: default body (stature %.2f m)",
                  cfg_.enabled ? "no standing frame yet" : "automatic calibration off", report_.stature);
    break_window();
  }

  // A time discontinuity (reset, gap): the current window ends without being used.
  // The tracker stream exchanged the controllers (trackers/controller_swap.hpp): the calibration's
  // offsets follow their devices (Calibration::swap_controllers), and an open window, whose frames
  // had the old roles, is dropped.
  void swap_controllers() noexcept {
    calib_.swap_controllers();
    break_window();
  }

  void break_window() noexcept {
    rise_run_ = false;
    held_ = 0;
    run_ = 0;
    seg_active_ = used_stand_ = prov_open_ = false;
    early_next_ = -std::numeric_limits<double>::infinity();
    prev_valid_.fill(false);
    have_prev_time_ = false;
  }

  // An explicit calibration (a T-pose or a chosen standing frame, or set by the application):
  // used as given, the search stops until recalibrate(). time: of the frame used (NaN: none).
  void set_explicit(const Calibration& c, CalibrationSource source, double time = std::numeric_limits<double>::quiet_NaN()) noexcept {
    manual_ = true;
    calib_ = c;
    CalibrationReport r;
    r.status = CalibrationStatus::Calibrated;
    r.source = source;
    r.first_time = r.last_time = time;
    if (std::isfinite(time)) r.first_frame = r.last_frame = frame_;
    r.scale = c.scale;
    r.floor = c.floor;
    r.eye_height = (std::isfinite(c.scale) && c.scale > 0 ? standard_head_ / c.scale : standard_head_) + devices_.eye.y();
    r.stature = r.eye_height / cfg_.eye_height_ratio;
    r.confidence = source == CalibrationSource::Explicit ? 0.5 : 1.0;
    r.windows = 0;
    if (source == CalibrationSource::Explicit)
      std::snprintf(r.message, sizeof r.message, "explicit: one frame at %.2f s, stature %.2f m", time, r.stature);
    else
      std::snprintf(r.message, sizeof r.message, "set by the application: scale %.3f (stature ~%.2f m)", c.scale, r.stature);
    report_ = r;
    break_window();
  }

  // Calibrate from one given frame (T-pose or standing: upright, facing forward) with the device
  // model and the head-based scale; the search stops until recalibrate(). False (unchanged) when
  // the frame cannot be used.
  bool calibrate_from(const trackers::TrackerFrame& f, double standard_hips_height = 0) noexcept {
    Calibration c;
    if (!c.from_tpose(f, standard_hips_height > 0 ? standard_hips_height : standard_hips_, standard_head_, devices_,
                      ScaleFrom::Head))
      return false;
    set_explicit(c, CalibrationSource::Explicit, f.time);
    return true;
  }

  bool searching() const noexcept { return cfg_.enabled && !manual_; }
  bool manual() const noexcept { return manual_; }  // an explicit calibration is in use
  const Calibration& calibration() const noexcept { return calib_; }
  const CalibrationReport& report() const noexcept { return report_; }
  const AutoCalibrationConfig& config() const noexcept { return cfg_; }
  const DeviceModel& devices() const noexcept { return devices_; }
  double standard_head_height() const noexcept { return standard_head_; }
  // The default body (s = 1): the standard skeleton's head joint plus the eye offset, / 0.936.
  double default_stature() const noexcept { return (standard_head_ + devices_.eye.y()) / cfg_.eye_height_ratio; }

 private:
  // The standing-window search of push().
  bool search(double time, const Poses& pose, const Flags& valid) noexcept {
    Sample s;
    const bool ok = qualify(time, pose, valid, s);
    qualified_ = ok;
    remember(time, pose, valid);
    if (!ok) return end_run();
    if (held_ == kCapacity) {  // full: close the window before its first frame is dropped
      if (seg_active_ && seg_start_ == run_ - held_) {
        const bool changed = close_window();
        used_stand_ = true;
        append(s);
        return changed;
      }
    }
    append(s);
    long long start = 0;
    WindowStats w;
    const bool still = trailing_window(start, w, early() ? cfg_.first_window : cfg_.min_window);
    if (!still) {
      used_stand_ = false;
      return seg_active_ ? close_window() : false;
    }
    if (used_stand_) return false;
    if (!seg_active_) seg_active_ = true, seg_start_ = start;
    seg_end_ = run_ - 1;
    if (at(seg_end_).t - at(seg_start_).t >= cfg_.max_window - 1e-9) {
      used_stand_ = true;
      return close_window();
    }
    // the provisional estimate: tried when the stand reaches first_window, then every quarter second
    if (early() && est_n_ == 0 && at(seg_end_).t >= early_next_) {
      early_next_ = at(seg_end_).t + 0.25;
      return close_window(/*keep_open=*/true);
    }
    return false;
  }

  // The first upright headset frame of a search with no estimate: enlarge the default body to its
  // eye height when that is above the default's (and the stature plausible). True when that
  // changed calibration(). Done once per search (recalibrate() allows it again).
  bool size_from_headset(const Poses& pose, const Flags& valid) noexcept {
    if (!cfg_.size_from_headset || floor_estimated() || est_n_ > 0 || report_.status != CalibrationStatus::Default) {
      sized_ = true;
      return false;
    }
    if (!valid[0] || !finite(pose[0])) return false;
    if (!upright(pose[0].orientation.normalized().toRotationMatrix())) return false;  // wait for a frame that is
    sized_ = true;
    const double eye = pose[0].position.y() - calib_.floor;
    const double stature = eye / cfg_.eye_height_ratio;
    const bool larger = stature > default_stature() * 1.01;
    const bool smaller = cfg_.size_from_headset_both_ways && stature < default_stature() * 0.99 && stature >= cfg_.min_stature;
    if (!(larger || smaller) || !(stature <= cfg_.max_stature)) return false;
    const double s = scale_of_eye(eye);
    if (!(s > 0) || !std::isfinite(s)) return false;
    calib_.scale = s;
    report_.stature = stature;
    report_.eye_height = eye;
    report_.scale = s;
    report_.sized_from_headset = true;
    report_.sized_lower_bound = !cfg_.size_from_headset_both_ways;
    std::snprintf(report_.message, sizeof report_.message,
                  report_.sized_lower_bound ? "no standing frame yet: default body sized to the headset (stature >= %.2f m)"
                         : "no standing frame yet: default body sized to the first upright headset frame (stature ~%.2f m)",
                  stature);
    return true;
  }

  // A bent stand. The stillness tests pass in a crouch, a lean or a runner's set position, and
  // such a window underestimates the stature (offdist devices mode: the 12 of 61 validation clips
  // whose held first frame is such a stance were sized 4-10 % small). Nobody walks with their eyes
  // above their standing eye height, so when the (upright) headset of a walking user (horizontal
  // speed > rise_walk_speed) stays more than rise_margin above the estimate's eye height for
  // rise_time s, the estimate is raised to the lowest headset height of that run. Frames that could
  // be a stand do not count (a stand gives a new window, with orientations); neither do tiptoes
  // (standing) or a jump (vertical speed > rise_max_vertical_speed ends the run: a jump spends
  // ~0.2 s below 1 m/s). With a pelvis tracker its height is re-set at the run's mean
  // (Calibration::set_pelvis_height). The orientation offsets are kept: a moving user's frames
  // are no calibration pose. True when calibration() changed.
  // The headset's velocity v from the previous frame search() remembered (valid, within
  // max_frame_gap); false when there is none.
  bool head_velocity(double time, const Poses& pose, const Flags& valid, Eigen::Vector3d& v) const noexcept {
    const double dt = time - prev_time_;
    if (!std::isfinite(time) || !valid[0] || !finite(pose[0]) || !have_prev_time_ || !prev_valid_[0] || !(dt > 0) ||
        dt > cfg_.max_frame_gap)
      return false;
    v = (pose[0].position - prev_pos_[0]) / dt;
    return true;
  }

  // v: the headset's velocity (head_velocity()).
  bool rise(double time, const Poses& pose, const Flags& valid, const Eigen::Vector3d& v) noexcept {
    const bool ok = cfg_.rise_margin > 0 && est_n_ > 0 && !floor_estimated() && !qualified_ &&
                    report_.status == CalibrationStatus::Calibrated &&
                    upright(pose[0].orientation.normalized().toRotationMatrix()) &&
                    pose[0].position.y() > est_eye_ + cfg_.rise_margin &&
                    std::hypot(v.x(), v.z()) > cfg_.rise_walk_speed && std::abs(v.y()) < cfg_.rise_max_vertical_speed;
    if (!ok || (rise_run_ && !(time - rise_prev_t_ > 0 && time - rise_prev_t_ <= cfg_.max_frame_gap))) {
      rise_run_ = false;
      if (!ok) return false;
    }
    const double y = pose[0].position.y();
    if (!rise_run_) {
      rise_run_ = true;
      rise_t0_ = time;
      rise_min_ = y;
      rise_pelvis_ = 0;
      rise_pelvis_n_ = 0;
    }
    rise_prev_t_ = time;
    rise_min_ = std::min(rise_min_, y);
    if (valid[3] && finite(pose[3])) rise_pelvis_ += pose[3].position.y(), ++rise_pelvis_n_;
    if (time - rise_t0_ < cfg_.rise_time - 1e-9) return false;
    rise_run_ = false;
    const double eye = rise_min_ - calib_.floor, stature = eye / cfg_.eye_height_ratio;
    if (!(stature <= cfg_.max_stature) || !(scale_of_eye(eye) > 0)) return false;
    const double from = report_.stature;
    est_eye_ = est_lo_ = est_hi_ = rise_min_;
    est_n_ = 1;
    provisional_ = false;
    calib_.scale = scale_of_eye(eye);
    if (rise_pelvis_n_ > 0) calib_.set_pelvis_height(rise_pelvis_ / rise_pelvis_n_, standard_hips_, devices_);
    CalibrationReport& r = report_;
    ++r.raised;
    r.eye_height = eye;
    r.stature = stature;
    r.scale = calib_.scale;
    r.provisional = false;
    r.confidence = std::min(r.confidence, 0.5);
    std::snprintf(r.message, sizeof r.message,
                  "automatic: stature %.2f m (raised from %.2f m: the headset stayed above the stand's height at %.1f-%.1f s, a bent stand), "
                  "orientations from standing at %.1f-%.1f s",
                  stature, from, rise_t0_, time, r.first_time, r.last_time);
    return true;
  }

  // The headset's up axis near world up (its Y column's y).
  bool upright(const Eigen::Matrix3d& R) const noexcept { return R(1, 1) > cfg_.min_up_y; }
  bool level_head() const noexcept { return cfg_.level_head && devices_.eye.squaredNorm() > 0; }
  static double tilt_degrees(const Eigen::Quaterniond& q) noexcept {  // the headset's up axis from world up
    return std::acos(std::clamp(q.normalized().toRotationMatrix()(1, 1), -1.0, 1.0)) * 180.0 / M_PI;
  }
  // s = standard head-joint height / the user's (eye height above the floor - e.y).
  double scale_of_eye(double eye) const noexcept { return standard_head_ / (eye - devices_.eye.y()); }

  struct Sample {
    double t = 0;
    long long frame = 0;
    Eigen::Vector3d head = Eigen::Vector3d::Zero();
    double eye_y = 0;     // the headset's height as the head would have it upright (level_head), else head.y()
    double pelvis_y = 0;  // the pelvis tracker's height (when valid[3])
    double head_speed = 0;
    std::array<double, 2> ctl_speed{};
    std::array<bool, 2> ctl_speed_valid{};
    std::array<Eigen::Quaterniond, trackers::kTrackerCount> q;
    Flags valid{};
  };
  struct WindowStats {
    double mean_speed = 0, range = 0;
  };

  static bool finite(const trackers::PoseD& p) noexcept { return p.position.allFinite() && p.orientation.coeffs().allFinite(); }

  // The per-frame conditions; fills s. Needs the previous frame's headset (for its speed).
  bool qualify(double time, const Poses& pose, const Flags& valid, Sample& s) const noexcept {
    if (!std::isfinite(time) || !valid[0] || !finite(pose[0])) return false;
    const double dt = time - prev_time_;
    if (!have_prev_time_ || !prev_valid_[0] || !(dt > 0) || dt > cfg_.max_frame_gap) return false;
    const Eigen::Quaterniond qh = pose[0].orientation.normalized();
    const Eigen::Matrix3d R = qh.toRotationMatrix();
    if (!upright(R) || !(std::abs(R(1, 2)) < cfg_.max_forward_y)) return false;  // up.y, forward.y = -Z.y
    const Eigen::Vector3d& p = pose[0].position;
    s.head_speed = (p - prev_pos_[0]).norm() / dt;
    if (!(s.head_speed < cfg_.max_head_speed)) return false;
    for (int c = 0; c < 2; ++c) {
      const int k = 1 + c;
      s.ctl_speed_valid[c] = false;
      if (!valid[k] || !finite(pose[k])) continue;
      const Eigen::Vector3d d = pose[k].position - p;
      if (!(-d.y() >= cfg_.controller_below) || !(std::hypot(d.x(), d.z()) <= cfg_.controller_horizontal)) return false;
      if (prev_valid_[k]) {
        s.ctl_speed[c] = (pose[k].position - prev_pos_[k]).norm() / dt;
        s.ctl_speed_valid[c] = std::isfinite(s.ctl_speed[c]);
      }
    }
    s.t = time;
    s.frame = frame_ - 1;
    s.head = p;
    s.eye_y = p.y();
    if (level_head())  // head joint height (the eye offset e turned with the headset) + e.y
      s.eye_y = p.y() - R.row(1).dot(eye_in_headset_) + devices_.eye.y();
    s.pelvis_y = pose[3].position.y();
    for (int k = 0; k < trackers::kTrackerCount; ++k) {
      s.valid[k] = valid[k] && finite(pose[k]);
      s.q[k] = s.valid[k] ? pose[k].orientation : Eigen::Quaterniond::Identity();
    }
    return true;
  }

  void remember(double time, const Poses& pose, const Flags& valid) noexcept {
    if (!std::isfinite(time)) return;
    prev_time_ = time;
    have_prev_time_ = true;
    for (int k = 0; k < trackers::kTrackerCount; ++k) {
      prev_valid_[k] = valid[k] && finite(pose[k]);
      if (prev_valid_[k]) prev_pos_[k] = pose[k].position;
    }
  }

  // A frame that does not qualify: the run ends, an open window is closed.
  bool end_run() noexcept {
    const bool changed = seg_active_ ? close_window() : false;
    held_ = 0;
    run_ = 0;
    used_stand_ = false;
    return changed;
  }

  void append(const Sample& s) noexcept {
    ring_[static_cast<std::size_t>(run_ % kCapacity)] = s;
    ++run_;
    held_ = std::min(held_ + 1, kCapacity);
  }
  const Sample& at(long long a) const noexcept { return ring_[static_cast<std::size_t>(a % kCapacity)]; }

  // The first stand of a search is judged on first_window (the provisional estimate, then the
  // window that replaces it), every later one on min_window.
  bool early() const noexcept { return cfg_.first_window > 0 && (est_n_ == 0 || prov_open_); }

  // The shortest trailing window spanning `span` s; true when it passes the stillness tests.
  bool trailing_window(long long& start, WindowStats& w, double span) const noexcept {
    const long long newest = run_ - 1, oldest = run_ - held_;
    const double t1 = at(newest).t;
    long long a = newest;
    while (a > oldest && t1 - at(a).t < span - 1e-9) --a;
    if (t1 - at(a).t < span - 1e-9) return false;
    start = a;
    double sum = 0, lo = std::numeric_limits<double>::infinity(), hi = -lo, cs[2] = {0, 0};
    int cn[2] = {0, 0};
    const long long n = newest - a + 1;
    for (long long i = a; i <= newest; ++i) {
      const Sample& s = at(i);
      sum += s.head_speed;
      lo = std::min(lo, s.head.y());
      hi = std::max(hi, s.head.y());
      for (int c = 0; c < 2; ++c)
        if (s.ctl_speed_valid[c]) cs[c] += s.ctl_speed[c], ++cn[c];
    }
    w.mean_speed = sum / double(n);
    w.range = hi - lo;
    if (!(w.mean_speed < cfg_.mean_head_speed) || !(w.range < cfg_.head_height_range)) return false;
    for (int c = 0; c < 2; ++c)
      if (cn[c] > 0 && !(cs[c] / cn[c] < cfg_.controller_mean_speed)) return false;
    return true;
  }

  // The open window [seg_start_, seg_end_] becomes an estimate (or is refused / skipped).
  // keep_open: the provisional first estimate; the window grows on and replaces it when it closes.
  bool close_window(bool keep_open = false) noexcept {
    seg_active_ = keep_open;
    const bool own = !keep_open && prov_open_;  // the window the provisional estimate came from
    if (!keep_open) {
      prov_open_ = false;
      early_next_ = -std::numeric_limits<double>::infinity();
    }
    const long long a0 = seg_start_, a1 = seg_end_;
    const int n = static_cast<int>(a1 - a0 + 1);
    if (n < 2) return false;
    const double duration = at(a1).t - at(a0).t;
    // A window shorter than min_window (the user moved on) is no estimate; when it is the
    // provisional one's, that stays provisional until a full window confirms or replaces it.
    if (!keep_open && duration < cfg_.min_window - 1e-9) return false;
    double sum = 0, lo = std::numeric_limits<double>::infinity(), hi = -lo;
    std::array<long long, trackers::kTrackerCount> best{};
    std::array<double, trackers::kTrackerCount> best_score;
    best_score.fill(std::numeric_limits<double>::infinity());
    for (long long i = a0; i <= a1; ++i) {
      const Sample& s = at(i);
      heights_[static_cast<std::size_t>(i - a0)] = s.eye_y;
      sum += s.head_speed;
      lo = std::min(lo, s.head.y());
      hi = std::max(hi, s.head.y());
      double score = s.head_speed;
      for (int c = 0; c < 2; ++c)
        if (s.ctl_speed_valid[c]) score += s.ctl_speed[c];
      for (int k = 0; k < trackers::kTrackerCount; ++k)
        if (s.valid[k] && score < best_score[k]) best_score[k] = score, best[k] = i;
    }
    double* h = heights_.data();
    std::nth_element(h, h + n / 2, h + n);
    double eye_raw = h[n / 2];
    if (n % 2 == 0) eye_raw = 0.5 * (eye_raw + *std::max_element(h, h + n / 2));
    const double mean_speed = sum / n, range = hi - lo;
    const double stillness = std::clamp(1 - 0.5 * mean_speed / cfg_.mean_head_speed - 0.5 * range / cfg_.head_height_range, 0.0, 1.0);
    const double quality = 0.5 * std::min(1.0, duration / cfg_.max_window) + 0.5 * stillness;
    // y = 0 is not the floor (no estimate yet, and eyes this low are nobody's standing): estimate it
    if (!floor_estimated() && est_n_ == 0 && !provisional_ && cfg_.floor_fallback_eye > 0 && eye_raw < cfg_.floor_fallback_eye)
      floor_fallback_ = true;
    const double stature = floor_estimated() ? cfg_.assumed_stature : eye_raw / cfg_.eye_height_ratio;
    // A full window replaces a provisional estimate (unless lower: sitting), and its own window
    // keeps the provisional orientation offsets when the height agrees: the same stand, so only the
    // size moves, by a refinement.
    const bool was_provisional = provisional_ && !keep_open;
    const bool keep_offsets = own && std::abs(eye_raw - est_eye_) <= cfg_.agreement;
    const bool plausible = stature >= cfg_.min_stature && stature <= cfg_.max_stature;
    if (was_provisional && plausible && (own || eye_raw - est_eye_ >= -cfg_.agreement)) est_n_ = 0, provisional_ = false;
    const bool have = est_n_ > 0;
    if (keep_open) {  // provisional: only a plausible first estimate; the whole window judges the rest
      if (have || !plausible || stillness < cfg_.first_window_stillness) return false;
      provisional_ = prov_open_ = true;
    }
    const double diff = have ? eye_raw - est_eye_ : 0.0;
    if (have && diff < -cfg_.agreement) {  // lower: sitting or crouching
      ++report_.skipped;
      describe();
      return false;
    }
    if (!plausible) {
      ++report_.refused;
      if (!have) {
        report_.status = CalibrationStatus::Refused;
        report_.first_frame = at(a0).frame, report_.last_frame = at(a1).frame;
        report_.first_time = at(a0).t, report_.last_time = at(a1).t;
        std::snprintf(report_.message, sizeof report_.message,
                      "refused: standing at %.1f-%.1f s gives stature %.2f m, outside [%.2f, %.2f] m: default body (stature %.2f m)",
                      at(a0).t, at(a1).t, stature, cfg_.min_stature, cfg_.max_stature, report_.stature);
      } else {
        describe();
      }
      return false;
    }
    rise_run_ = false;
    if (!have || diff > cfg_.agreement) {  // first, or higher: (re)place the estimate
      if (have) ++report_.replaced;
      est_n_ = 1;
      est_eye_ = eye_raw;
      est_lo_ = est_hi_ = eye_raw;
      est_quality_ = quality;
      if (!keep_offsets) {
        Calibration c = Calibration::uncalibrated(devices_);
        for (int k = 0; k < trackers::kTrackerCount; ++k) {
          const bool grip = k == 1 || k == 2;
          if (!std::isfinite(best_score[k])) {  // not tracked in this window: a controller keeps its offset
            if (grip) c.offset[k] = calib_.offset[k];
            continue;
          }
          Eigen::Quaterniond o;
          if (!grip) {
            o = window_offset(at(best[k]), k);
          } else if (!held_grip(at(best[k]), k, o)) {  // keeps the one it has (the device model's, or an earlier window's)
            c.offset[k] = calib_.offset[k];
            continue;
          } else {
            grip_set_[k - 1] = true;
          }
          c.offset[k] = o;
        }
        calib_ = c;
      }
    } else {  // the same stand height: averaged in
      // (the orientation offsets of the estimate are kept, except a controller's that no window
      // gave yet: this one's, if it is held)
      for (int k = 1; k <= 2; ++k) {
        Eigen::Quaterniond o;
        if (grip_set_[k - 1] || !std::isfinite(best_score[k])) continue;
        if (held_grip(at(best[k]), k, o)) calib_.offset[k] = o, grip_set_[k - 1] = true;
      }
      est_eye_ = (est_eye_ * est_n_ + eye_raw) / (est_n_ + 1);
      est_quality_ = (est_quality_ * est_n_ + quality) / (est_n_ + 1);
      est_lo_ = std::min(est_lo_, eye_raw);
      est_hi_ = std::max(est_hi_, eye_raw);
      ++est_n_;
    }
    calib_.floor = floor_estimated() ? est_eye_ - cfg_.eye_height_ratio * cfg_.assumed_stature : 0.0;
    const double eye = est_eye_ - calib_.floor;
    calib_.scale = scale_of_eye(eye);
    if (std::isfinite(best_score[3])) calib_.set_pelvis_height(at(best[3]).pelvis_y, standard_hips_, devices_);
    const double agree = est_n_ >= 2 ? (1 - 1.0 / est_n_) * std::max(0.0, 1 - (est_hi_ - est_lo_) / cfg_.agreement) : 0.0;
    CalibrationReport& r = report_;
    r.status = CalibrationStatus::Calibrated;
    r.source = CalibrationSource::Automatic;
    r.sized_from_headset = false;
    r.first_frame = at(a0).frame, r.last_frame = at(a1).frame;
    r.first_time = at(a0).t, r.last_time = at(a1).t;
    r.eye_height = eye;
    r.stature = eye / cfg_.eye_height_ratio;
    r.scale = calib_.scale;
    r.floor = calib_.floor;
    r.floor_estimated = floor_estimated();
    r.floor_not_at_zero = floor_fallback_ && !cfg_.estimate_floor;
    r.confidence = std::clamp(est_quality_ * (0.7 + 0.3 * agree), 0.0, 1.0);
    r.windows = est_n_;
    r.provisional = provisional_;
    r.grip_default[0] = !grip_set_[0];
    r.grip_default[1] = !grip_set_[1];
    describe();
    return true;
  }

  // o_k = q_k^-1 Yaw(headset forward) at a window's sample (the pelvis: times pelvis_standing).
  Eigen::Quaterniond window_offset(const Sample& s, int k) const noexcept {
    if (k == 0 && level_head() && tilt_degrees(s.q[0]) > cfg_.level_head_min_tilt) return DeviceModel::default_orientation_offset();
    Eigen::Matrix3d target = Calibration::facing(s.q[0]);
    if (k == 3) target = target * devices_.pelvis_standing.toRotationMatrix();
    return Eigen::Quaterniond(s.q[k].normalized().toRotationMatrix().transpose() * target);
  }
  // Controller k's offset o at a window's sample; true when it is held as a hand at a stand holds
  // it (max_grip_deviation), else the window is counted in report_.grips_not_held.
  bool held_grip(const Sample& s, int k, Eigen::Quaterniond& o) noexcept {
    o = window_offset(s, k);
    if (!(cfg_.max_grip_deviation > 0)) return true;
    const double a = o.angularDistance(DeviceModel::default_orientation_offset());
    if (std::isfinite(a) && a <= cfg_.max_grip_deviation * M_PI / 180.0) return true;
    ++report_.grips_not_held;
    return false;
  }

  // The one-line message of a calibrated report (with the windows not used, if any).
  void describe() noexcept {
    CalibrationReport& r = report_;
    if (r.status != CalibrationStatus::Calibrated || r.source != CalibrationSource::Automatic) {
      if (r.status == CalibrationStatus::Default && !r.sized_from_headset)
        std::snprintf(r.message, sizeof r.message, "no standing frame yet: default body (stature %.2f m)", default_stature());
      return;
    }
    char extra[128] = "";
    int len = 0;
    if (r.skipped || r.refused)
      len = std::snprintf(extra, sizeof extra, "; not used: %d lower (sitting?), %d implausible", r.skipped, r.refused);
    if ((r.grip_default[0] || r.grip_default[1]) && len >= 0 && len < int(sizeof extra))
      std::snprintf(extra + len, sizeof extra - len, "; %s grip%s not seen held: device model's",
                    r.grip_default[0] && r.grip_default[1] ? "both" : r.grip_default[0] ? "left" : "right",
                    r.grip_default[0] && r.grip_default[1] ? "s" : "");
    if (r.floor_estimated)
      std::snprintf(r.message, sizeof r.message, "automatic: standing at %.1f-%.1f s, floor estimated at y = %.2f m%s (stature assumed %.2f m), %d window%s%s",
                    r.first_time, r.last_time, r.floor, r.floor_not_at_zero ? ", y = 0 is not the floor" : "",
                    r.stature, r.windows, r.windows == 1 ? "" : "s", extra);
    else
      std::snprintf(r.message, sizeof r.message, "automatic%s: standing at %.1f-%.1f s, stature %.2f m, confidence %.2f, %d window%s%s",
                    r.provisional ? " (provisional)" : "", r.first_time, r.last_time, r.stature,
                    r.confidence, r.windows, r.windows == 1 ? "" : "s", extra);
  }

  bool floor_estimated() const noexcept { return cfg_.estimate_floor || floor_fallback_; }

  AutoCalibrationConfig cfg_;
  DeviceModel devices_;
  Eigen::Vector3d eye_in_headset_;  // e in the headset's own (OpenXR) frame: level_head's per-frame eye height
  bool floor_fallback_ = false;  // y = 0 was found not to be the floor (floor_fallback_eye)
  double standard_head_ = 1.38;
  double standard_hips_ = 0;
  bool manual_ = false;
  Calibration calib_;
  CalibrationReport report_;
  long long frame_ = 0;  // frames pushed since construction / recalibrate()
  // the previous frame (speeds)
  bool have_prev_time_ = false;
  double prev_time_ = 0;
  Flags prev_valid_{};
  std::array<Eigen::Vector3d, trackers::kTrackerCount> prev_pos_{};
  // the current run of qualifying frames (ring) and its open window
  std::array<Sample, kCapacity> ring_{};
  std::array<double, kCapacity> heights_{};
  long long run_ = 0;  // frames appended to the run
  int held_ = 0;       // of which the ring holds the newest
  bool seg_active_ = false, used_stand_ = false;
  bool provisional_ = false;  // the estimate is the first stand's early one (first_window)
  double early_next_ = -std::numeric_limits<double>::infinity();  // next provisional try (s)
  bool prov_open_ = false;    // the provisional estimate's window is still open
  bool sized_ = false;        // size_from_headset has looked at an upright headset frame
  // rise(): the current run of headset frames above the estimate
  bool rise_run_ = false;
  bool qualified_ = false;  // the last frame passed the stand search's per-frame tests
  double rise_t0_ = 0, rise_prev_t_ = 0, rise_min_ = 0, rise_pelvis_ = 0;
  int rise_pelvis_n_ = 0;
  long long seg_start_ = 0, seg_end_ = 0;
  // the estimate
  int est_n_ = 0;
  std::array<bool, 2> grip_set_{};  // a window gave the left / right controller's offset
  double est_eye_ = 0, est_lo_ = 0, est_hi_ = 0, est_quality_ = 0;
};

}  // namespace sparsebody::features
