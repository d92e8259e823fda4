// Foot contact locking, one foot: the joint IK holds in place while the foot is in contact.
//   contact turns on   -> the joint's position at that frame becomes the lock target, either at a
//                         given height (LoBSTr, paper §3.4.1: the toe base at its standing height
//                         above the floor) or at its own height (Neural3Points direct mode, §7: the
//                         ankle); leg IK holds the joint there while contact stays on;
//   contact turns off  -> for `blend_frames` frames (LoBSTr 10, Neural3Points 8) the target moves
//                         from the lock position to the predicted joint position with the
//                         slow-in-slow-out weight w_k = (1 - cos(pi k / n)) / 2, then IK stops;
//   contact on again while blending -> locks at the current blended position.
// A lock the leg cannot reach any more (further than `max_reach` from the hip), or one the
// predicted joint has left by more than `max_drift` (the network says the foot is elsewhere: a
// missed contact release), is released through the same blend and held off: it does not lock again
// until the contact flag has gone off once. Rearm says whether the release frame's own "off"
// counts (SameFrame, LoBSTr) or only a later one does (NextFrame, Neural3Points). With replant
// (LoBSTr), a foot whose contact stays on through the release locks again where the network puts
// it once the blend is over: a re-planted foot instead of one that follows a drifting network.
// hold(true) (the user stands still, trackers/stillness.hpp): a locked foot stays locked whatever
// the contact flag or the drift says, so the avatar's feet do not creep while the user stands; a
// lock the hip has left out of reach slides back into reach on the floor (at most 20 cm per frame,
// else it is released). The pipeline clears the hold on the first moving frame. Under hold
// a free foot in contact that the network moves less than `hold_rearm_step` per frame locks even
// when held off (a drift release while walking otherwise left it following the network's creep
// for the whole stand: 30 % of the feet in offdist's csv stands); a foot the network still moves
// (stepping with the head still) stays free. A foot locked under hold locks where it was shown the
// frame before (the prediction may just have jumped, e.g. a calibration restarted the network) and
// settles to the lock height over `blend_frames` instead of snapping down.
// Orientation (orient(), show(), stop()): while the user stands still a locked foot keeps the
// orientation it was planted with, eased in and out over `blend_frames`. The lock holds one point
// (LoBSTr's toe, direct mode's ankle), so a foot the network turns about it moves the rest of the
// foot: heel-up for a step it will not take (the leg then cannot reach and the toe slides), or
// 1.2 cm/s of creep at direct mode's toes.
#pragma once
#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace sparsebody::pose {

class FootLock {
 public:
  enum class State { Free, Locked, Blending };
  enum class Rearm { SameFrame, NextFrame };

  explicit FootLock(int blend_frames = 10, Rearm rearm = Rearm::SameFrame) : n_(blend_frames), rearm_(rearm) {}
  // Free, nothing shown; the rearm step is kept.
  void reset() noexcept {
    state_ = State::Free;
    hold_off_ = hold_ = shown_ = foot_shown_ = just_locked_ = false;
    settle_ = n_;
    plant_w_ = 0;
    contact_y_ = std::numeric_limits<double>::infinity();
  }
  void hold(bool h) noexcept { hold_ = h; }
  // The world's scale changed by k (a new calibration: positions are in the standard skeleton's
  // scale): the lock moves with the ground (x and z x k); heights are the body's, kept.
  void rescale(double k) noexcept {
    for (Eigen::Vector3d* p : {&lock_, &from_, &current_, &last_joint_}) p->x() *= k, p->z() *= k;
  }
  State state() const noexcept { return state_; }
  // Where the joint is locked (meaningful while state() is Locked; before the height easing).
  const Eigen::Vector3d& lock_position() const noexcept { return lock_; }
  // Lock now where the foot was last shown, moved with the ground (x and z x k), easing to
  // `lock_height` (nullptr: its own height, or the height of its last walking contact where that is
  // lower, as far as the leg reaches: a swing foot caught in the air is put down; in offdist's
  // csvstop stands 19 % of Neural3Points' toe frames were more than 6 cm up, 8.5 % now); a foot
  // never shown resets. For the two moments the network's foot must not be followed: it
  // restarted while the user stands (a calibration changed
  // the body's size by k: its first pose is a default stance, and free feet snapped to it, up to
  // 24 cm in one frame in offdist's csv), and the user just stopped dead (trackers::Stillness's
  // stop test, k = 1: the network walks on for a step or so).
  // The foot also keeps the orientation it was shown with (show()), at once.
  void lock_in_place(double k = 1.0, const double* lock_height = nullptr) noexcept {
    if (!shown_) { reset(); return; }
    Eigen::Vector3d p = current_;
    p.x() *= k, p.z() *= k;
    const bool hold = hold_;  // as the caller set it for this frame
    const double contact_y = contact_y_;
    const bool foot_shown = foot_shown_;
    reset();
    hold_ = hold;
    contact_y_ = contact_y;
    foot_shown_ = foot_shown;
    state_ = State::Locked;
    from_ = lock_ = current_ = last_joint_ = p;
    lock_.y() = lock_height ? *lock_height : std::min(p.y(), contact_y_);
    caught_y_ = p.y();
    settle_ = 0;
    shown_ = true;
    plant_as_shown();
  }
  // The user just stopped (trackers::Stillness::stopped_now()), before this frame's update(): the
  // foot stays as it was shown last frame, locked (a lock from the walk keeps its place) and planted
  // with its shown orientation at once (not the lock's older one).
  void stop(const double* lock_height = nullptr) noexcept {
    if (state_ != State::Locked) lock_in_place(1.0, lock_height);
    else plant_as_shown();
  }

  // After an update() that returned true: `foot`, the foot joint's world rotation this frame, turns
  // towards the orientation it was planted with (the one it had when it locked, or as shown at a
  // stop or a restart) while `still`; eased in and out over blend_frames. A foot that locks while
  // still is planted at once: it has its planted orientation already.
  void orient(Eigen::Quaterniond& foot, bool still) noexcept {
    const bool locked = state_ == State::Locked;
    if (locked && just_locked_) {
      planted_ = foot;
      if (still) plant_w_ = 1;
    }
    plant_w_ += std::clamp((locked && still ? 1.0 : 0.0) - plant_w_, -1.0 / n_, 1.0 / n_);
    if (plant_w_ > 0) foot = foot.slerp(plant_w_, planted_).normalized();
  }
  // The foot joint's world rotation as output this frame (after IK): what stop() and lock_in_place()
  // plant. Call it every frame after update().
  void show(const Eigen::Quaterniond& foot) noexcept {
    shown_foot_ = foot;
    foot_shown_ = true;
  }
  // The orientation a foot locked while still keeps (orient()); turn_planted(dq) turns it by dq
  // (world frame): Neural3Points lowers a heel a stop left up (pose::lower_heel).
  const Eigen::Quaterniond& planted() const noexcept { return planted_; }
  void turn_planted(const Eigen::Quaterniond& dq) noexcept { planted_ = (dq * planted_).normalized(); }
  // Moves a lock vertically by dy with what it was made from (Neural3Points: held feet on a step
  // rise with the head while the user stands; avatar/n3p_direct.hpp).
  void raise(double dy) noexcept {
    for (Eigen::Vector3d* p : {&lock_, &from_, &current_}) p->y() += dy;
    caught_y_ += dy;
    if (std::isfinite(contact_y_)) contact_y_ += dy;
  }
  // The last show()n rotation; nullptr when none since reset() (lock_in_place() keeps it).
  const Eigen::Quaterniond* shown_foot() const noexcept { return foot_shown_ ? &shown_foot_ : nullptr; }
  // Under hold, how far (m per frame, the joint's units) the network's joint may move for a held-off
  // free foot to lock; the pipelines set speed / frame rate. Kept by reset().
  void set_hold_rearm_step(double metres) noexcept { rearm_step_ = metres; }
  // Replant (LoBSTr): a foot released while its contact stays on locks again where the network
  // has it once the release blend is over, instead of following the network until the contact
  // goes off once (kept by reset()).
  void set_replant(bool on) noexcept { replant_ = on; }

  // One frame: contact state, the predicted joint (toe) position, the hip position and the leg's
  // reach; a new lock is put at `lock_height`. Returns true when IK must place the joint at `target`.
  bool update(bool contact, const Eigen::Vector3d& joint, const Eigen::Vector3d& hip, double max_reach, double max_drift,
              double lock_height, Eigen::Vector3d& target) noexcept {
    return step(contact, joint, hip, max_reach, max_drift, &lock_height, target);
  }
  // The same with a new lock at the joint's own height (the ankle pin of direct mode).
  bool update(bool contact, const Eigen::Vector3d& joint, const Eigen::Vector3d& hip, double max_reach, double max_drift,
              Eigen::Vector3d& target) noexcept {
    return step(contact, joint, hip, max_reach, max_drift, nullptr, target);
  }

 private:
  bool step(bool contact, const Eigen::Vector3d& joint, const Eigen::Vector3d& hip, double max_reach, double max_drift,
              const double* lock_height, Eigen::Vector3d& target) noexcept {
    const bool predicted_contact = contact;
    const bool was_locked = state_ == State::Locked;
    if (rearm_ == Rearm::NextFrame && !predicted_contact) hold_off_ = false;
    const bool shown = shown_;  // current_ and last_joint_ are last frame's (current_ set below on every path)
    const Eigen::Vector3d prev_joint = last_joint_;
    shown_ = true;
    last_joint_ = joint;
    just_locked_ = false;
    if (hold_ && state_ == State::Locked) {
      if (!((lock_ - hip).norm() <= max_reach)) slide_into_reach(hip, max_reach);
      if ((lock_ - hip).norm() <= max_reach) {
        target = current_ = locked_target();
        return true;
      }
    }
    if (state_ == State::Locked && ((lock_ - hip).norm() > max_reach || (lock_ - joint).norm() > max_drift)) {
      contact = false;
      hold_off_ = true;  // do not re-lock until the contact goes off once
    }
    if (rearm_ == Rearm::SameFrame && !predicted_contact) hold_off_ = false;
    if (hold_ && contact && state_ != State::Locked && shown && (joint - prev_joint).norm() <= rearm_step_ &&
        (joint - hip).norm() <= max_reach)
      hold_off_ = false;
    if (replant_ && contact && state_ == State::Free && (joint - hip).norm() <= max_reach) hold_off_ = false;
    if (hold_off_) contact = false;
    switch (state_) {
      case State::Free:
        if (contact) {
          state_ = State::Locked;
          // under hold: where the foot was shown last frame (the prediction may have jumped, e.g.
          // after a calibration restarted the network), settling from its height
          from_ = hold_ && shown ? current_ : joint;
          lock_ = from_;
          if (lock_height) lock_.y() = *lock_height;
          else if (hold_) lock_.y() = std::min(lock_.y(), contact_y_);  // put down, as lock_in_place
          else contact_y_ = lock_.y();  // a walking contact: the joint's height on the floor
          caught_y_ = from_.y();
          settle_ = hold_ ? 0 : n_;
        }
        break;
      case State::Locked:
        if (!contact) { state_ = State::Blending; from_ = lock_; k_ = 0; }
        break;
      case State::Blending:
        if (contact) { state_ = State::Locked; lock_ = current_; caught_y_ = lock_.y(); settle_ = n_; }
        break;
    }
    if (state_ == State::Locked) {
      just_locked_ = !was_locked;
      target = current_ = locked_target();
      return true;
    }
    if (state_ == State::Blending) {
      ++k_;
      const double w = 0.5 - 0.5 * std::cos(M_PI * k_ / n_);
      target = current_ = (1 - w) * from_ + w * joint;
      if (k_ >= n_) state_ = State::Free;
      return true;
    }
    current_ = joint;
    plant_w_ = 0;  // free: the predicted orientation
    return false;
  }

  // Under hold, a lock the hip has left out of reach moves towards the hip on the floor, its height
  // kept, just back into reach (the foot slides as far as the hip moved) instead of being released
  // to the network's foot. At a stop the network's hips walk on for a few frames; a trailing foot
  // locked at full stretch was released by a 1 cm hip move and blended to the network's foot, up
  // to 2.5 m/s in offdist's csv stands. A slide longer than kHoldSlideStep (a hip that jumped or
  // walked away), or a lock below or above the hip by more than the reach, stays out of reach
  // (released). The bound: after a stop from a run the anchored hips settle 5-20 cm a frame for a
  // frame or two (offdist csv, Neural3Points: feet while still 0.94 cm/s with 20 cm, 1.10 with 5 cm).
  static constexpr double kHoldSlideStep = 0.2;  // m per frame (6 m/s at 30 Hz)
  // A lock put below the height it was caught at first rises as far as the leg needs, no higher.
  void slide_into_reach(const Eigen::Vector3d& hip, double max_reach) noexcept {
    if (lock_.y() < caught_y_) {
      const double h2 = (Eigen::Vector2d(lock_.x() - hip.x(), lock_.z() - hip.z())).squaredNorm();
      const double r2v = max_reach * max_reach - h2;
      if (r2v > 0) lock_.y() = std::clamp(hip.y() - std::sqrt(r2v) * (1 - 1e-9), lock_.y(), caught_y_);
      if ((lock_ - hip).norm() <= max_reach) return;
    }
    const double dy = lock_.y() - hip.y();
    const Eigen::Vector2d h(lock_.x() - hip.x(), lock_.z() - hip.z());
    const double r2 = max_reach * max_reach - dy * dy, n = h.norm();
    if (!(r2 > 0) || !(n > 0)) return;
    const double r = std::sqrt(r2) * (1 - 1e-9);
    if (!(n - r <= kHoldSlideStep)) return;
    const Eigen::Vector2d p = h * (r / n);
    lock_.x() = hip.x() + p.x(), lock_.z() = hip.z() + p.y();
  }

  void plant_as_shown() noexcept {
    planted_ = shown_foot_;
    plant_w_ = 1;
  }

  // The lock; for a foot locked in the air while still (settle_ < n_), eased down to its height.
  Eigen::Vector3d locked_target() noexcept {
    if (settle_ >= n_) return lock_;
    ++settle_;
    const double w = 0.5 - 0.5 * std::cos(M_PI * settle_ / n_);
    return {lock_.x(), (1 - w) * from_.y() + w * lock_.y(), lock_.z()};
  }

  int n_;
  Rearm rearm_;
  State state_ = State::Free;
  int k_ = 0, settle_ = n_;  // settle_ < n_: a hold lock still easing down to its height
  double rearm_step_ = 0.004;  // 0.12 m/s at 30 Hz
  bool replant_ = false;
  bool hold_off_ = false, hold_ = false, shown_ = false;  // shown_: current_ and last_joint_ are last frame's
  bool foot_shown_ = false;  // shown_foot_ holds a show()n rotation
  Eigen::Vector3d lock_ = Eigen::Vector3d::Zero(), from_ = Eigen::Vector3d::Zero(), current_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d last_joint_ = Eigen::Vector3d::Zero();  // the network's joint, last frame
  bool just_locked_ = false;  // the last update() locked the foot (it was not locked before)
  // height of the joint at its last walking contact (own-height locks); +inf: none yet
  double contact_y_ = std::numeric_limits<double>::infinity();
  double caught_y_ = 0;  // the joint's height when the lock was made (a lock put lower may rise back to it)
  Eigen::Quaterniond planted_ = Eigen::Quaterniond::Identity();     // the orientation kept while still
  Eigen::Quaterniond shown_foot_ = Eigen::Quaterniond::Identity();  // the last output's (show())
  double plant_w_ = 0;  // how much of planted_ the locked foot keeps (0..1)
};

}  // namespace sparsebody::pose
