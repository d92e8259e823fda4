// Is the user standing still? From the headset alone (every pipeline has it), per model frame:
// its horizontal speed and yaw rate, each low-passed over ~0.2 s. Still once both stay below the
// "enter" thresholds for `enter_seconds`; moving again as soon as one exceeds its "leave"
// threshold (hysteresis, so that sway does not flicker it). Turning on the spot is not still: the
// feet must be free to step round. Used to hold foot locks (pose::FootLock::hold) so that the
// avatar's feet do not creep while the user stands (issue 12: <= 1 cm/s standing still).
#pragma once
#include <algorithm>
#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace sparsebody::trackers {

struct StillnessConfig {
  double enter_speed = 0.06;  // m/s, horizontal headset speed (low-passed)
  double leave_speed = 0.15;
  double enter_yaw_rate = 0.35;  // rad/s (20 deg/s)
  double leave_yaw_rate = 0.8;
  double enter_seconds = 0.3;
  double time_constant = 0.2;  // s, of the low-pass
  // A stop: the headset has stayed within `stop_radius` (horizontally) and `stop_yaw` of where it
  // is now over the last `stop_seconds`, after moving. Still at once, and the filtered speeds
  // restart below the entry thresholds: a walker who stops dead is otherwise "moving" for ~0.9 s
  // while the low-pass decays, and the networks walk on for a step. offdist, every 5th
  // validation clip, feet while still in the csv stands (a dead stop): LoBSTr 3.21 -> 0.80 cm/s,
  // Neural3Points 2.85 -> 1.46 (0.2 s and 1.5 cm: 1.22 / 1.85); nominal MPJPE not worse. 0 s: off.
  double stop_seconds = 0.1;
  double stop_radius = 0.01;  // m
  double stop_yaw = 0.03;     // rad (1.7 deg: below 17 deg/s over 0.1 s)
};

class Stillness {
 public:
  explicit Stillness(StillnessConfig c = {}) : cfg_(c) {}
  void reset() noexcept { have_ = false; still_ = stop_ = false; calm_ = 0; speed_ = yaw_rate_ = 0; n_ = 0; }
  bool still() const noexcept { return still_; }
  // This frame's update found a stop (the stop test, not the slow entry): the user was moving and
  // now stands, so both feet are on the floor whatever a network still says.
  bool stopped_now() const noexcept { return stop_; }
  // Positions given in a scale that changed by k (a new calibration): keep the history consistent.
  void rescale(double k) noexcept {
    p_.x() *= k, p_.z() *= k;
    for (Eigen::Vector3d& r : ring_) r.x() *= k, r.y() *= k;  // (x, z, yaw): the stop test's history too
  }
  // The positions' frame changed (a new calibration's offsets and scale): the next frame starts
  // the difference again; the filtered speeds and the still state carry on.
  void rebase() noexcept { have_ = false; n_ = 0; }
  // The caller knows the user stands (the calibrator just accepted a standing window): still now,
  // unless the filtered motion already says otherwise; leaving works as usual.
  void assume_still() noexcept {
    if (speed_ <= cfg_.leave_speed && yaw_rate_ <= cfg_.leave_yaw_rate) still_ = true;
  }
  double speed() const noexcept { return speed_; }
  double yaw_rate() const noexcept { return yaw_rate_; }

  // The headset's position and orientation (any consistent scale: thresholds are in that unit per
  // second; the pipelines pass the calibrated, standard-scale pose) and the frame's duration.
  bool update(const Eigen::Vector3d& p, const Eigen::Quaterniond& q, double dt) noexcept {
    const Eigen::Vector3d f = q * Eigen::Vector3d::UnitZ();
    const double yaw = std::atan2(f.x(), f.z());
    stop_ = false;
    if (!(dt > 0) || !p.allFinite() || !std::isfinite(yaw)) { reset(); return false; }
    if (have_) {
      const double v = std::hypot(p.x() - p_.x(), p.z() - p_.z()) / dt;
      const double w = std::abs(std::remainder(yaw - yaw_, 2 * M_PI)) / dt;
      const double a = 1.0 - std::exp(-dt / cfg_.time_constant);
      speed_ += a * (v - speed_);
      yaw_rate_ += a * (w - yaw_rate_);
      if (still_) {
        if (speed_ > cfg_.leave_speed || yaw_rate_ > cfg_.leave_yaw_rate) still_ = false, calm_ = 0;
      } else {
        calm_ = (speed_ < cfg_.enter_speed && yaw_rate_ < cfg_.enter_yaw_rate) ? calm_ + dt : 0;
        still_ = calm_ >= cfg_.enter_seconds;
        if (!still_ && calm_ == 0 && stopped(p, yaw, dt)) {
          still_ = stop_ = true;
          calm_ = cfg_.enter_seconds;
          speed_ = std::min(speed_, cfg_.enter_speed);
          yaw_rate_ = std::min(yaw_rate_, cfg_.enter_yaw_rate);
        }
      }
    }
    have_ = true;
    p_ = p;
    yaw_ = yaw;
    ring_[head_] = {p.x(), p.z(), yaw};
    head_ = (head_ + 1) % kRing;
    n_ = std::min(n_ + 1, kRing);
    return still_;
  }

 private:
  // The stop test over the ring of past frames (the newest not yet in it).
  bool stopped(const Eigen::Vector3d& p, double yaw, double dt) const noexcept {
    if (!(cfg_.stop_seconds > 0)) return false;
    const int need = static_cast<int>(std::ceil(cfg_.stop_seconds / dt - 1e-9));
    if (need > n_ || need < 1) return false;  // not enough history (or a window longer than the ring)
    for (int i = 1; i <= need; ++i) {
      const Eigen::Vector3d& r = ring_[(head_ - i + kRing) % kRing];
      // written as !(<=) so that a NaN radius or angle in the config means no stop, not always
      if (!(std::hypot(p.x() - r.x(), p.z() - r.y()) <= cfg_.stop_radius) ||
          !(std::abs(std::remainder(yaw - r.z(), 2 * M_PI)) <= cfg_.stop_yaw))
        return false;
    }
    return true;
  }

  static constexpr int kRing = 16;  // frames of history for the stop test (0.2 s needs 6 at 30 Hz)
  StillnessConfig cfg_;
  Eigen::Vector3d ring_[kRing];  // (x, z, yaw) of past frames
  int head_ = 0, n_ = 0;
  bool have_ = false, still_ = false, stop_ = false;
  double calm_ = 0, speed_ = 0, yaw_rate_ = 0, yaw_ = 0;
  Eigen::Vector3d p_ = Eigen::Vector3d::Zero();
};

}  // namespace sparsebody::trackers
