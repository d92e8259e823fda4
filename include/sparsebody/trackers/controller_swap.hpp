// Swapped controllers: symmetric controllers (HTC Vive wands, trackers used as hands) get their
// left / right roles from the runtime, which assigns them by where they were when turned on, so a
// user often holds the "left" one in the right hand. The networks then see crossed hands for the
// whole session, and the avatar's arms cross.
// ControllerSwapDetector looks, per input frame, at each controller's sideways offset in the
// headset's heading frame: x_k = (p_k - p_head) . left, left = world up x the horizontal forward.
// Forward is the body's: Z of the calibrated headset q_head o_head, so the detector takes the
// pipeline's o_head (a half turn about Y before calibration, as OpenXR devices look along -Z; the
// identity for trackers already in the body convention).
// Evidence comes only from frames where crossing the hands is awkward and rare: the headset
// upright, both controllers valid, at least `min_below` under the headset (hands at the sides or
// hips, not at the chest), within `max_horizontal` of it (held, not on a table) and more than
// `min_apart` apart sideways. Such a frame is "crossed" (x_left - x_right < -min_apart) or "normal"
// (> min_apart); each tally is a leaky sum of seconds (time constant `memory`). The roles are
// exchanged when the crossed tally reaches `evidence` and `share` of both, and back the same way.
// Both controllers lost or out of reach for `put_down_time` (put down: they may be picked up the
// other way round) start the tallies again.
// On the 301 validation and 3 CMU clips as device sessions: 0.13 s of crossed frames in all (one
// clip) against 659 s of normal ones. Found `evidence` (~1.6 s) after the start of a swapped
// session or a swapped pick-up; a swap in mid-session without a put-down once the normal frames
// are forgotten enough (~8 s into a walk) (tests/calibration/test_controller_swap.cpp).
// TrackerStream applies the exchange before anything else sees the frame, restarts the tick clock
// at the decision (both hands jump ~0.5 m) and counts it; the kinematic pipelines exchange their
// calibration's controller orientation offsets with the devices (Calibration::swap_controllers).
// Off with enabled = false. No allocation.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include <Eigen/Geometry>

#include "sparsebody/trackers/types.hpp"

namespace sparsebody::trackers {

struct ControllerSwapConfig {
  bool enabled = true;
  double min_below = 0.4;       // m: both controllers at least this far below the headset
  double max_horizontal = 0.8;  // m: ... and within this of it horizontally
  double min_apart = 0.2;       // m: sideways apart by more than this in the heading frame
  double evidence = 1.5;        // s of crossed frames (leaky) before the roles are swapped
  double share = 0.75;          // ... and at least this share of all evidence
  double memory = 10.0;         // s: time constant of the leaky tallies
  double max_dt = 0.25;         // s: a longer step between frames adds no evidence
  // Both controllers out of every hand (invalid, or further than put_down_distance from the headset)
  // for put_down_time: they were put down, and may be picked up the other way round, so the tallies
  // start again (a swap at the pick-up is then found after `evidence`, not after forgetting).
  double put_down_distance = 1.5;  // m (the sanitizer's max_controller_distance)
  double put_down_time = 1.0;      // s
};

class ControllerSwapDetector {
 public:
  // o_head of an uncalibrated OpenXR headset: half a turn about Y (features::DeviceModel).
  static Eigen::Quaterniond openxr_head_offset() noexcept { return Eigen::Quaterniond(0, 0, 1, 0); }

  explicit ControllerSwapDetector(ControllerSwapConfig cfg = {}, double quat_tolerance = 0.1) noexcept
      : cfg_(cfg), quat_tolerance_(quat_tolerance) {}

  // Forgets the evidence and the swap (a new session); count() keeps counting.
  void reset() noexcept {
    crossed_ = normal_ = put_down_ = 0;
    swapped_ = false;
    have_time_ = false;
  }
  bool swapped() const noexcept { return swapped_; }  // the roles are exchanged now
  int count() const noexcept { return count_; }       // decisions since construction

  // One input frame as recorded; true when the roles change at this frame. Then (and from then
  // on) apply() exchanges the controllers. head_offset: the calibration's o_head (see above).
  bool push(const TrackerFrame& f, const Eigen::Quaterniond& head_offset = openxr_head_offset()) noexcept {
    double dt = have_time_ ? f.time - last_time_ : 0.0;
    if (!(dt > 0) || dt > cfg_.max_dt) dt = 0;  // NaN, repeated or far apart: no evidence
    if (std::isfinite(f.time)) last_time_ = f.time, have_time_ = true;
    if (!cfg_.enabled || dt == 0) return false;
    const double keep = std::exp(-dt / cfg_.memory);
    crossed_ *= keep;
    normal_ *= keep;
    // each pose checked once: headset, left, right as recorded
    std::array<PoseD, 3> p;
    std::array<bool, 3> ok{};
    for (int k = 0; k < 3; ++k) ok[k] = f.valid[k] && checked_pose(f.pose[k], quat_tolerance_, p[k]);
    put_down_ = put_down(p, ok) ? put_down_ + dt : 0.0;
    if (put_down_ >= cfg_.put_down_time) crossed_ = normal_ = 0;
    const int side = crossing(p, ok, head_offset);  // of the frame as the pipelines would see it (swapped or not)
    if (side < 0) crossed_ += dt;
    if (side > 0) normal_ += dt;
    if (crossed_ < cfg_.evidence || crossed_ < cfg_.share * (crossed_ + normal_)) return false;
    swapped_ = !swapped_;
    std::swap(crossed_, normal_);  // the same frames, seen through the new roles
    ++count_;
    return true;
  }

  // The frame with the roles as decided: left and right controller exchanged when swapped().
  void apply(TrackerFrame& f) const noexcept {
    if (!swapped_) return;
    std::swap(f.pose[1], f.pose[2]);
    std::swap(f.valid[1], f.valid[2]);
  }

 private:
  // Neither controller in a hand: invalid, unusable or out of reach of a measured headset.
  bool put_down(const std::array<PoseD, 3>& p, const std::array<bool, 3>& ok) const noexcept {
    if (!ok[0]) return false;  // no headset: nothing to judge by
    for (int k = 1; k < 3; ++k)
      if (ok[k] && (p[k].position - p[0].position).norm() <= cfg_.put_down_distance) return false;
    return true;
  }

  // -1 crossed, +1 normal, 0 no evidence; the roles as apply() would give them.
  int crossing(const std::array<PoseD, 3>& p, const std::array<bool, 3>& ok, const Eigen::Quaterniond& head_offset) const noexcept {
    if (!ok[0] || !ok[1] || !ok[2]) return 0;
    const PoseD& h = p[0];
    PoseD a = p[1], b = p[2];
    if (swapped_) std::swap(a, b);
    const Eigen::Matrix3d R = (h.orientation * head_offset).toRotationMatrix();  // the body's facing frame
    if (R(1, 1) < 0.8) return 0;  // upright
    Eigen::Vector3d fwd = R.col(2);
    fwd.y() = 0;
    if (!(fwd.norm() > 1e-6)) return 0;
    const Eigen::Vector3d left = Eigen::Vector3d::UnitY().cross(fwd.normalized());
    for (const PoseD* c : {&a, &b}) {
      const Eigen::Vector3d d = c->position - h.position;
      if (-d.y() < cfg_.min_below || std::hypot(d.x(), d.z()) > cfg_.max_horizontal) return 0;
    }
    const double dx = (a.position - h.position).dot(left) - (b.position - h.position).dot(left);
    return dx < -cfg_.min_apart ? -1 : dx > cfg_.min_apart ? 1 : 0;
  }

  ControllerSwapConfig cfg_;
  double quat_tolerance_ = 0.1;
  double crossed_ = 0, normal_ = 0;  // leaky seconds of evidence
  double put_down_ = 0;              // s both controllers have been out of every hand
  double last_time_ = 0;
  bool have_time_ = false;
  bool swapped_ = false;
  int count_ = 0;
};

}  // namespace sparsebody::trackers
