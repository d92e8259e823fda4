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
  explicit RecenterDetector(RecenterConfig cfg = {}) : cfg_(cfg) {}

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
  static bool usable(const TrackerFrame& f, int k) noexcept {
    const Posef& p = f.pose[k];
    const double n = std::sqrt(double(p.orientation.x) * p.orientation.x + double(p.orientation.y) * p.orientation.y +
                               double(p.orientation.z) * p.orientation.z + double(p.orientation.w) * p.orientation.w);
    return f.valid[k] && std::isfinite(p.position.x) && std::isfinite(p.position.y) && std::isfinite(p.position.z) &&
           std::isfinite(n) && std::abs(n - 1) < 0.1;
  }

  bool rigid_jump(const TrackerFrame& a, const TrackerFrame& b, double dt) const noexcept {
    if (!usable(a, 0) || !usable(b, 0)) return false;
    const double deg = M_PI / 180;
    const Eigen::Quaterniond qa = to_eigen(a.pose[0].orientation).normalized(), qb = to_eigen(b.pose[0].orientation).normalized();
    const Eigen::Matrix3d D = (qb * qa.conjugate()).toRotationMatrix();  // the headset's turn, world frame
    if (D(1, 1) < std::cos(cfg_.tolerance_deg * deg)) return false;    // not about the vertical
    const double psi = std::atan2(D(0, 2) - D(2, 0), D(0, 0) + D(2, 2));
    const Eigen::Matrix3d Y = Eigen::AngleAxisd(psi, Eigen::Vector3d::UnitY()).toRotationMatrix();
    const Eigen::Vector3d pa = to_eigen(a.pose[0].position), pb = to_eigen(b.pose[0].position);
    const Eigen::Vector3d t = pb - Y * pa;
    bool large = std::abs(psi) > cfg_.min_turn_deg * deg || (pb - pa).norm() > cfg_.min_shift;
    const double tol = cfg_.tolerance + cfg_.max_speed * dt;
    int agree = 0;
    for (int k = 1; k < kTrackerCount; ++k) {
      if (!usable(a, k) || !usable(b, k)) continue;
      const Eigen::Vector3d ka = to_eigen(a.pose[k].position), kb = to_eigen(b.pose[k].position);
      if ((kb - (Y * ka + t)).norm() > tol) return false;
      const Eigen::Quaterniond ra = to_eigen(a.pose[k].orientation).normalized(), rb = to_eigen(b.pose[k].orientation).normalized();
      if (rb.angularDistance(Eigen::Quaterniond(Y) * ra) > cfg_.tolerance_deg * deg) return false;
      large = large || (kb - ka).norm() > cfg_.min_shift;
      ++agree;
    }
    return large && agree > 0;
  }

  RecenterConfig cfg_;
  TrackerFrame prev_{};
  bool have_ = false;
  int count_ = 0;
};

}  // namespace sparsebody::trackers
