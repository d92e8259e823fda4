// Bad tracker input, made defined (per model frame, no allocation):
//   - NaN/Inf anywhere in a pose, or a quaternion whose norm is off 1 by more than 10 %: the
//     tracker is treated as invalid this frame (near-unit quaternions are renormalised);
//   - a tracker marked invalid: its last good pose is held (velocities become zero, so the
//     network's input decays to "standing still"); the pelvis, if lost, follows the headset's
//     horizontal motion from the moment it was lost;
//   - a controller further than `max_controller_distance` (1.5 m) from the headset: not in a hand
//     (put down, dropped), held like an invalid one;
//   - a position jump over `max_jump` (1 m) in one model frame: treated as a glitch, the frame is
//     rejected as invalid; after `relock_frames` consecutive rejections the new place is accepted
//     and the caller is told to reset (the tracking origin moved);
//   - the headset (or every tracker) invalid for longer than `max_hold` seconds: reset requested;
//     until valid input returns the output holds its last pose;
//   - every tracker turned and shifted together between two input frames (a recentred tracking
//     space, `recenter`): found by TrackerStream before resampling, a reset at that frame;
//   - the left and right controllers held in the other hands (`controller_swap`): TrackerStream
//     exchanges them from the frame where that is clear, a reset there.
#pragma once
#include <cmath>

#include "sparsebody/trackers/controller_swap.hpp"
#include "sparsebody/trackers/recenter.hpp"
#include "sparsebody/trackers/types.hpp"

namespace sparsebody::trackers {

struct SanitizerConfig {
  double max_jump = 1.0;        // metres per model frame
  double max_hold = 0.5;        // seconds of headset loss before a reset
  int relock_frames = 3;        // consecutive jumped frames accepted as a new origin
  double quat_tolerance = 0.1;  // |1 - |q|| above this is invalid
  // m: a controller further than this from the headset measured in the same frame is in no hand
  // (put down on a table, dropped): held like a lost one. 1.5 m is beyond a 2.2 m user's reach
  // (Neural3Points' controller_max_distance, its own check, is the same). <= 0: off.
  double max_controller_distance = 1.5;
  RecenterConfig recenter{};    // the tracking space turned / shifted between two frames (TrackerStream)
  ControllerSwapConfig controller_swap{};  // left / right controllers held in the other hands (TrackerStream)
};

// Output of one sanitised frame: poses to use (held where needed) and flags.
struct SanitizedFrame {
  std::array<PoseD, kTrackerCount> pose;
  std::array<bool, kTrackerCount> measured{};  // true: this frame's own data was used
  bool usable = false;                          // false before any valid headset frame
  bool reset = false;                           // state should restart (long loss, origin jump)
};

class TrackerSanitizer {
 public:
  explicit TrackerSanitizer(SanitizerConfig c = {}) : cfg_(c) {}

  void reset() noexcept {
    have_.fill(false);
    held_.fill(0.0);
    jumps_.fill(0);
    away_.fill(false);
    have_head_prev_ = false;
  }

  // The last process() result (its reset flag: the C API's SB_POSE_RESET).
  const SanitizedFrame& last() const noexcept { return out_; }

  // dt: model frame period (s). Returns the poses to feed forward.
  const SanitizedFrame& process(const TrackerFrame& in, double dt) noexcept {
    out_.reset = false;
    for (int k = 0; k < kTrackerCount; ++k) {
      PoseD p;
      bool ok = in.valid[k] && check(in.pose[k], p);
      if (ok && (k == 1 || k == 2) && cfg_.max_controller_distance > 0 && out_.measured[0] &&
          !((p.position - last_[0].position).norm() <= cfg_.max_controller_distance)) {
        ok = false;  // in no hand (the headset, k = 0, was measured above in this frame)
        away_[k] = true;
      }
      if (ok && away_[k]) {  // back in a hand: wherever it was put down is no glitch to hold
        away_[k] = false;
        jumps_[k] = 0;
      } else if (ok && have_[k] && (p.position - last_[k].position).norm() > cfg_.max_jump) {
        if (++jumps_[k] < cfg_.relock_frames) ok = false;
        else out_.reset = true;  // the tracker really moved (recentred space): accept and restart
      } else if (ok) {
        jumps_[k] = 0;
      }
      out_.measured[k] = ok;
      if (ok) {
        last_[k] = p;
        have_[k] = true;
        held_[k] = 0;
      } else {
        held_[k] += dt;
      }
    }
    constexpr int H = static_cast<int>(Tracker::Head), P = static_cast<int>(Tracker::Pelvis);
    // A lost pelvis follows the headset horizontally (keeps the reference frame moving with the user).
    if (!out_.measured[P] && have_[P] && out_.measured[H] && have_head_prev_) {
      Eigen::Vector3d d = last_[H].position - head_prev_;
      d.y() = 0;
      last_[P].position += d;
    }
    if (out_.measured[H]) { head_prev_ = last_[H].position; have_head_prev_ = true; }
    if (!have_[P] && have_[H]) {  // never seen a pelvis: put one below the head, facing its yaw
      last_[P].position = last_[H].position;
      last_[P].position.y() *= 0.66;  // standing hips/head height ratio of the standard skeleton
      last_[P].orientation = last_[H].orientation;
    }
    if (held_[H] > cfg_.max_hold) out_.reset = true;
    out_.usable = have_[H];
    for (int k = 0; k < kTrackerCount; ++k) {
      out_.pose[k] = last_[k];
      if (!have_[k]) out_.pose[k] = last_[H];  // hands never seen: at the head (held still)
    }
    return out_;
  }

 private:
  bool check(const Posef& in, PoseD& out) const noexcept { return checked_pose(in, cfg_.quat_tolerance, out); }

  SanitizerConfig cfg_;
  std::array<PoseD, kTrackerCount> last_{};
  std::array<bool, kTrackerCount> have_{};
  std::array<double, kTrackerCount> held_{};
  std::array<int, kTrackerCount> jumps_{};
  std::array<bool, kTrackerCount> away_{};  // a controller out of every hand's reach (max_controller_distance)
  Eigen::Vector3d head_prev_ = Eigen::Vector3d::Zero();
  bool have_head_prev_ = false;
  SanitizedFrame out_;
};

}  // namespace sparsebody::trackers
