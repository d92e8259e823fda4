// Loss of balance (Neural3Points §9: the simulated character can fall where the policy fails; the
// system must recover). Checked once per 30 Hz frame on the simulated root against the reference
// (predicted) root:
//   - root height below `min_height` (absolute, m) or more than `max_drop` below the reference;
//   - root tilt (angle between the root's up axis and the world up) above `max_tilt` (rad) while
//     the reference is within that limit (a user lying down is not a fall);
//   - tracking error |p_root - p_ref| above `max_error` for `error_frames` consecutive frames
//     (a diverging character).
// A detection tells the caller to reset the simulated character to the predicted pose and resume
// (see avatar/n3p_physics.hpp). Counts are kept for reporting.
#pragma once
#include <algorithm>
#include <cmath>

#include <Eigen/Core>

namespace sparsebody::control {

struct FallDetectorConfig {
  double min_height = 0.35;   // m, root (hips) height
  double max_drop = 0.35;     // m below the reference root
  double max_tilt = 1.05;     // rad (60 deg)
  double max_error = 0.5;     // m
  int error_frames = 15;      // consecutive frames (0.5 s at 30 Hz)
};

enum class FallReason : unsigned char { None, Height, Tilt, Diverged };

class FallDetector {
 public:
  explicit FallDetector(FallDetectorConfig cfg = {}) : cfg_(cfg) {}

  void reset() noexcept { over_ = 0; }

  // root_up: the root's up axis in the world (R e_y); ref_up likewise for the reference.
  FallReason update(const Eigen::Vector3d& root, const Eigen::Vector3d& root_up, const Eigen::Vector3d& ref,
                    const Eigen::Vector3d& ref_up) noexcept {
    FallReason r = FallReason::None;
    const double tilt = std::acos(std::clamp(root_up.normalized().y(), -1.0, 1.0));
    const double ref_tilt = std::acos(std::clamp(ref_up.normalized().y(), -1.0, 1.0));
    over_ = (root - ref).norm() > cfg_.max_error ? over_ + 1 : 0;
    if (!(root.y() >= cfg_.min_height) || !(ref.y() - root.y() <= cfg_.max_drop)) r = FallReason::Height;
    else if (tilt > cfg_.max_tilt && ref_tilt <= cfg_.max_tilt) r = FallReason::Tilt;
    else if (over_ >= cfg_.error_frames) r = FallReason::Diverged;
    if (r != FallReason::None) {
      ++falls_;
      over_ = 0;
    }
    return r;
  }

  long long falls() const noexcept { return falls_; }
  const FallDetectorConfig& config() const noexcept { return cfg_; }

 private:
  FallDetectorConfig cfg_;
  int over_ = 0;
  long long falls_ = 0;
};

}  // namespace sparsebody::control
