// Foot contact post-processing (paper §3.4.1), one foot:
//   contact turns on   -> the toe-base position at that frame, put at its standing height above
//                         the floor, becomes the lock target; leg IK holds the toe there while
//                         contact stays on;
//   contact turns off  -> for `blend_frames` (10) frames the target moves from the lock position
//                         to the network's toe position with the slow-in-slow-out weight
//                         w_k = (1 - cos(pi k / n)) / 2 (a shifted sine), then IK stops;
//   contact on again while blending -> locks at the current blended position.
// A lock the leg cannot reach any more (further than `max_reach` from the hip), or one the
// network's own toe has left by more than `max_drift` (it says the foot is elsewhere: a missed
// contact release), is released through the same blend, so a foot is never dragged behind.
#pragma once
#include <cmath>

#include <Eigen/Core>

namespace sparsebody::pose {

class FootLock {
 public:
  enum class State { Free, Locked, Blending };

  explicit FootLock(int blend_frames = 10) : n_(blend_frames) {}
  void reset() noexcept { state_ = State::Free; hold_off_ = false; }
  State state() const noexcept { return state_; }

  // One frame: contact state, the network's toe position, the hip position and the leg's reach.
  // Returns true when IK must place the toe at `target`.
  bool update(bool contact, const Eigen::Vector3d& toe, const Eigen::Vector3d& hip, double max_reach,
              double max_drift, double toe_height, Eigen::Vector3d& target) noexcept {
    const bool network_contact = contact;
    if (state_ == State::Locked && ((lock_ - hip).norm() > max_reach || (lock_ - toe).norm() > max_drift)) {
      contact = false;
      hold_off_ = true;  // do not re-lock until the network's contact goes off once
    }
    if (!network_contact) hold_off_ = false;
    if (hold_off_) contact = false;
    switch (state_) {
      case State::Free:
        if (contact) { state_ = State::Locked; lock_ = toe; lock_.y() = toe_height; }
        break;
      case State::Locked:
        if (!contact) { state_ = State::Blending; from_ = lock_; k_ = 0; }
        break;
      case State::Blending:
        if (contact) { state_ = State::Locked; lock_ = current_; }
        break;
    }
    if (state_ == State::Locked) {
      target = current_ = lock_;
      return true;
    }
    if (state_ == State::Blending) {
      ++k_;
      const double w = 0.5 - 0.5 * std::cos(M_PI * k_ / n_);
      target = current_ = (1 - w) * from_ + w * toe;
      if (k_ >= n_) state_ = State::Free;
      return true;
    }
    current_ = toe;
    return false;
  }

 private:
  int n_;
  State state_ = State::Free;
  int k_ = 0;
  bool hold_off_ = false;
  Eigen::Vector3d lock_ = Eigen::Vector3d::Zero(), from_ = Eigen::Vector3d::Zero(), current_ = Eigen::Vector3d::Zero();
};

}  // namespace sparsebody::pose
