// Loss of balance (Neural3Points §9: the simulated character can fall where the policy fails; the
// system must recover). Checked once per control period on the simulated root, against a reference
// root when there is one (Neural3Points: the predicted root) or alone (QuestSim):
//   - root height below `min_height` (absolute, m; a non-finite height counts) or more than
//     `max_drop` below the reference;
//   - root tilt (angle between the root's up axis and the world up) above `max_tilt` (rad) while
//     the reference is within that limit (a user lying down is not a fall); compared as the up
//     axis' vertical component against cos(max_tilt), in the caller's scalar S;
//   - tracking error |p_root - p_ref| above `max_error` for `error_frames` consecutive checks
//     (a diverging character).
// A detection tells the caller to reset the simulated character and resume (avatar/n3p_physics.hpp:
// onto the predicted pose; avatar/questsim.hpp: standing under the headset). Counts are kept for
// reporting.
#pragma once
#include <cmath>
#include <limits>

#include <Eigen/Core>

namespace sparsebody::control {

struct FallDetectorConfig {
  double min_height = 0.35;   // m, root (hips) height
  double max_drop = 0.35;     // m below the reference root
  double max_tilt = 1.05;     // rad (60 deg)
  double max_error = 0.5;     // m
  int error_frames = 15;      // consecutive checks (0.5 s at 30 Hz)
};

enum class FallReason : unsigned char { None, Height, Tilt, Diverged };

template <class S = double>
class FallDetector {
 public:
  using Vec3 = Eigen::Matrix<S, 3, 1>;

  explicit FallDetector(FallDetectorConfig cfg = {}) : cfg_(cfg), min_up_(S(std::cos(cfg.max_tilt))) {}

  void reset() noexcept { over_ = 0; }

  // One check against the reference: root / ref positions, root_up / ref_up their unit up axes
  // (R e_y). Counts the divergence frames and the falls.
  FallReason update(const Vec3& root, const Vec3& root_up, const Vec3& ref, const Vec3& ref_up) noexcept {
    over_ = (root - ref).norm() > S(cfg_.max_error) ? over_ + 1 : 0;
    FallReason r = posture(root, root_up, ref, ref_up);
    if (r == FallReason::None && over_ >= cfg_.error_frames) r = FallReason::Diverged;
    if (r != FallReason::None) {
      ++falls_;
      over_ = 0;
    }
    return r;
  }

  // The instantaneous rules (height, tilt), without the divergence count: no state changes.
  FallReason posture(const Vec3& root, const Vec3& root_up, const Vec3& ref, const Vec3& ref_up) const noexcept {
    if (!(root.y() >= S(cfg_.min_height)) || !(ref.y() - root.y() <= S(cfg_.max_drop))) return FallReason::Height;
    if (root_up.y() < min_up_ && ref_up.y() >= min_up_) return FallReason::Tilt;
    return FallReason::None;
  }
  // Without a reference (an upright one at the root's place): absolute height and tilt only.
  FallReason posture(const Vec3& root, const Vec3& root_up) const noexcept { return posture(root, root_up, root, Vec3::UnitY()); }

  long long falls() const noexcept { return falls_; }
  const FallDetectorConfig& config() const noexcept { return cfg_; }

 private:
  FallDetectorConfig cfg_;
  S min_up_;  // cos(max_tilt): the smallest vertical component of an upright-enough up axis
  int over_ = 0;
  long long falls_ = 0;
};

}  // namespace sparsebody::control
