// Recentring: a headset's "recenter" (or a runtime's re-localisation) turns and shifts the whole
// tracking space between two frames, so every tracker jumps by the same yaw and translation. Fed
// through the resampler as it is, the tick between the two frames mixes both worlds and the
// networks see one huge velocity: measured on every 6th validation walk (device sessions, a 90 deg
// / 0.5 m recentre at 3.5 s), the output left the user by 61 cm (LoBSTr) and 69 cm (Neural3Points)
// on average over the next 0.5 s, by up to 3.2-3.6 m.
// RecenterDetector compares each input frame with the previous one: a recentre is a change that is
// large (the headset turned > min_turn about the vertical, or a tracker moved > min_shift) and
// rigid: one yaw Y(psi) about world Y and one translation t, taken from the headset
// (t = p'_head - Y p_head), move every other tracker valid in both frames to within
// tolerance + max_speed dt of where it is (and its orientation within tolerance_deg), the
// headset's up axis kept. At least one tracker besides the headset must be there to agree.
// TrackerStream then restarts the tick clock at that frame (no tick mixes the two worlds) and the
// sanitizer accepts the new poses: the pipelines take it as a gap (their state restarts in the new
// world, the calibration is kept: its offsets are in the devices' own frames and a recentre keeps
// the floor). No allocation.
#pragma once
#include <cmath>

#include <Eigen/Geometry>

#include "sparsebody/trackers/types.hpp"

namespace sparsebody::trackers {

struct RecenterConfig {
  bool enabled = true;
  double min_turn_deg = 30;    // headset yaw change in one input frame (a spin at 720 deg/s is 24 deg at 30 Hz)
  double min_shift = 0.3;      // m: or a tracker moved this far in one frame
  double tolerance = 0.05;     // m: every other tracker where the rigid move puts it, within this
  double max_speed = 3.0;      // m/s: ... plus this much natural motion per second between the frames
  double tolerance_deg = 12;   // orientations and the headset's up axis within this
  double max_dt = 0.25;        // s: frames further apart are a gap anyway
};

class RecenterDetector {
 public:
  // quat_tolerance: the sanitizer's (SanitizerConfig), so both judge a pose alike (checked_pose).
  explicit RecenterDetector(RecenterConfig cfg = {}, double quat_tolerance = 0.1)
      : cfg_(cfg), quat_tolerance_(quat_tolerance), cos2_half_turn_(std::pow(std::cos(0.5 * cfg.min_turn_deg * M_PI / 180), 2)) {}

  void reset() noexcept { have_ = false; }
  int count() const noexcept { return count_; }  // recentres found since construction

  // One input frame; true when it is a recentred continuation of the previous one.
  bool push(const TrackerFrame& f) noexcept {
    const double dt = f.time - prev_.time;
    const bool found = cfg_.enabled && have_ && dt > 0 && dt <= cfg_.max_dt && rigid_jump(prev_, f, dt);
    if (found) ++count_;
    prev_ = f;
    have_ = std::isfinite(f.time);
    return found;
  }

 private:
  bool usable(const TrackerFrame& f, int k, PoseD& p) const noexcept { return f.valid[k] && checked_pose(f.pose[k], quat_tolerance_, p); }

  bool rigid_jump(const TrackerFrame& a, const TrackerFrame& b, double dt) const noexcept {
    if (!a.valid[0] || !b.valid[0]) return false;
    const double deg = M_PI / 180;
    const Eigen::Quaterniond qa = to_eigen(a.pose[0].orientation), qb = to_eigen(b.pose[0].orientation);
    const Eigen::Quaterniond d = qb * qa.conjugate();  // the headset's turn, world frame (|d| ~ 1)
    // Cheap first (every frame): is the change large at all? The turn's whole angle bounds its yaw;
    // a NaN fails every comparison here and is looked at below.
    bool large = d.w() * d.w() < cos2_half_turn_ * d.squaredNorm();
    const double shift2 = cfg_.min_shift * cfg_.min_shift;
    for (int k = 0; k < kTrackerCount && !large; ++k)
      large = a.valid[k] && b.valid[k] && (to_eigen(b.pose[k].position) - to_eigen(a.pose[k].position)).squaredNorm() > shift2;
    PoseD ha, hb;
    if (!large || !usable(a, 0, ha) || !usable(b, 0, hb)) return false;
    // Rigid about the vertical: one yaw Y and one translation t move every tracker.
    const Eigen::Matrix3d D = (hb.orientation * ha.orientation.conjugate()).toRotationMatrix();
    if (D(1, 1) < std::cos(cfg_.tolerance_deg * deg)) return false;  // the headset's up axis turned: not a recentre
    const double psi = std::atan2(D(0, 2) - D(2, 0), D(0, 0) + D(2, 2));
    const Eigen::Quaterniond Yq(Eigen::AngleAxisd(psi, Eigen::Vector3d::UnitY()));
    const Eigen::Matrix3d Y = Yq.toRotationMatrix();
    const Eigen::Vector3d t = hb.position - Y * ha.position;
    const double tol = cfg_.tolerance + cfg_.max_speed * dt;
    int agree = 0;
    for (int k = 1; k < kTrackerCount; ++k) {
      PoseD ka, kb;
      if (!usable(a, k, ka) || !usable(b, k, kb)) continue;
      if ((kb.position - (Y * ka.position + t)).norm() > tol) return false;
      if (kb.orientation.angularDistance(Yq * ka.orientation) > cfg_.tolerance_deg * deg) return false;
      ++agree;
    }
    return agree > 0;
  }

  RecenterConfig cfg_;
  double quat_tolerance_ = 0.1;
  double cos2_half_turn_ = 0;  // cos^2(min_turn / 2): a rotation turns more than min_turn when w^2 < this |q|^2
  TrackerFrame prev_{};
  bool have_ = false;
  int count_ = 0;
};

}  // namespace sparsebody::trackers
