// Arm length from controller reach (issue 12, "any body"): the output skeleton's arms are lengthened
// when the controllers are seen beyond their reach. A hand's IK cannot put the hand on a controller
// further from the shoulder than the arm is long: with the standard arms a long-armed user's hands
// come off the controllers whenever the arms stretch, the most visible error a VR avatar can make.
//   e = |p_hand - p_shoulder| / L   (L: the standard arm, upper arm + forearm; p_hand the
//                                    calibrated controller's wrist joint, standard scale)
// While e > a (the arm ratio in use) + margin for hold_time on either side, a rises to the least e
// of that run (within 1 + limit). Arms are only lengthened: a shorter arm than the standard still
// reaches every controller (its elbow bends more than the user's), and a relaxed arm is not
// straight enough to measure from: on validation device sessions an unknown grip offset (5-12 cm)
// moves e by ~6 %, as much as arms differ. The run's least e, and the hold, keep a tracking glitch,
// a single stretched frame or a grip held far out from raising it for good; a controller further
// than any arm (1 + limit + not_held) is not held and does not count. No allocation.
#pragma once
#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Core>

namespace sparsebody::pose {

struct ArmReachConfig {
  bool enabled = true;
  double margin = 0.01;     // beyond the reach in use, relative to the standard arm
  double hold_time = 0.2;   // s, seen that far out on consecutive measured frames
  double limit = 0.12;      // the ratio stays within 1 + limit (the training bodies' arms: +-8 %)
  // A controller further out than 1 + limit + not_held is not in a hand (put down on a table,
  // dropped, a tracking jump): that side's frame is no evidence of a long arm. 1.32: at 1.22, some of
  // the CMU clips' flung arms (trackers at the joints) stopped counting (LoBSTr +0.02 cm there).
  double not_held = 0.2;
};

class ArmReach {
 public:
  ArmReach() = default;
  explicit ArmReach(ArmReachConfig cfg) : cfg_(cfg) {}

  // e of one side: the controller's wrist joint's distance from the shoulder over the standard arm
  // L (pose::arm_length); NaN when the controller was not measured this frame.
  static double stretch(bool measured, const Eigen::Vector3d& hand, const Eigen::Vector3d& shoulder, double L) noexcept {
    return measured && L > 0 ? (hand - shoulder).norm() / L : std::numeric_limits<double>::quiet_NaN();
  }

  // The arm ratio in use (from `start`, the arms the body is known to have: 1 = standard).
  double ratio() const noexcept { return ratio_; }
  void reset(double start = 1.0) noexcept {
    ratio_ = std::isfinite(start) && start > 0 ? start : 1.0;
    end_run();
  }

  // One model frame: e of each side (NaN: not measured this frame: a lost or held controller).
  // True when the ratio changed.
  bool update(double e_left, double e_right, double dt) noexcept {
    if (!cfg_.enabled) return false;
    const double held = 1.0 + cfg_.limit + cfg_.not_held;
    auto in_hand = [&](double x) { return std::isfinite(x) && x <= held ? x : 0.0; };
    const double e = std::max(in_hand(e_left), in_hand(e_right));
    if (!(e > ratio_ + cfg_.margin) || !(dt > 0)) {
      end_run();
      return false;
    }
    run_time_ += dt;
    run_min_ = std::min(run_min_, e);
    if (run_time_ < cfg_.hold_time - 1e-9) return false;
    const double a = std::min(run_min_, 1.0 + cfg_.limit);
    end_run();  // a stretch that goes on raises again after another hold
    if (!(a > ratio_)) return false;
    ratio_ = a;
    return true;
  }

 private:
  void end_run() noexcept {
    run_time_ = 0;
    run_min_ = std::numeric_limits<double>::infinity();
  }

  ArmReachConfig cfg_{};
  double ratio_ = 1.0, run_time_ = 0, run_min_ = std::numeric_limits<double>::infinity();
};

}  // namespace sparsebody::pose
