// Did the user just stand up? From the headset alone (every pipeline has it): after resting at a
// height for a while (seated, crouched, kneeling: horizontally still, trackers/stillness.hpp), the
// headset rises well above that height, mostly vertically, and stays there.
//
// Why the pipelines care: the stillness detector watches horizontal motion only, so a user who sits
// is "still", and the foot locks it holds (pose::FootLock::hold) keep the feet where the seated pose
// put them; the networks never saw sitting, and their recurrent state after seconds of seated input
// is no standing user's. On validation device sessions that start with 5 s seated, the held feet
// stood 25-45 cm ahead of the user for the whole stand that followed (LoBSTr MPJPE after the
// stand-up 4.82 -> 7.57 cm); letting go of the locks alone put them again where the network still
// had its feet (9.14 cm). So at a stand-up the pipelines restart (reset_state(), as a calibration
// that resizes the body does): the network starts again from its standing state, and for 1 s
// (unheld_seconds, holding()) the feet follow it unheld before standing still holds them again.
// Every 5th validation clip (offdist seated): LoBSTr 7.57 -> 4.97 cm, Neural3Points 6.44 -> 5.50
// (without the seat: 4.82 / 5.57).
//
// World heights (metres, the reference space), not the calibration's scale: a session that starts
// seated is calibrated on the seated window (its stature is plausible), so in that scale the seated
// head is at standing height and the stand-up is a head above it.
//   rest:  still, within rest_band of one height, for rest_seconds (a bow or a quick crouch is
//          shorter, and moves)
//   up:    rise above the rest height for settle_seconds in a row, within max_horizontal of the
//          rest position (stairs move forwards; a jump comes down within settle_seconds)
//          -> update() returns true once
#pragma once
#include <cmath>

#include <Eigen/Core>

namespace sparsebody::trackers {

struct StandUpConfig {
  bool enabled = true;
  double rise = 0.25;            // m above the rest height: seated eyes are 0.35-0.5 m below standing ones
  double rest_seconds = 2.0;     // s still at one height before a rise counts
  double rest_band = 0.08;       // m: the rest height's range
  double settle_seconds = 0.4;   // s up in a row (a jump's flight is shorter)
  double max_horizontal = 0.4;   // m from the rest position (getting up moves the head ~0.2-0.3 m forwards)
  // s after a stand-up in which the pipelines hold no feet for standing still: the restarted
  // network's first stances are no place to hold them (validation sessions that start seated,
  // after the stand-up, 0 / 0.5 / 1 / 2 s: LoBSTr 5.04 / 5.01 / 4.97 / 5.02 cm, Neural3Points
  // 5.50 cm each; without the seat 4.82 / 5.57)
  double unheld_seconds = 1.0;
};

class StandUp {
 public:
  StandUp() = default;
  explicit StandUp(StandUpConfig c) noexcept : cfg_(c) {}
  void reset() noexcept { have_rest_ = false, rest_time_ = up_time_ = 0, unheld_ = 0; }
  // Whether feet may be held for standing still: not for unheld_seconds after a stand-up (counted
  // down by update(), the stand-up's own frame included).
  bool holding() const noexcept { return unheld_ == 0; }
  // Resting long enough that a rise would count.
  bool armed() const noexcept { return have_rest_ && rest_time_ >= cfg_.rest_seconds - 1e-9; }
  long long count() const noexcept { return count_; }  // stand-ups found since construction
  // One model frame of dt s: the headset's world position (metres) and whether the user stands
  // still (trackers::Stillness). True on the frame the user has been up for settle_seconds after
  // a rest. A non-finite position changes nothing.
  bool update(const Eigen::Vector3d& head, bool still, double dt) noexcept {
    const bool up = rise(head, still, dt);
    if (up) unheld_ = static_cast<int>(std::lround(cfg_.unheld_seconds / dt));
    if (unheld_ > 0) --unheld_;
    return up;
  }

 private:
  bool rise(const Eigen::Vector3d& head, bool still, double dt) noexcept {
    if (!cfg_.enabled || !head.allFinite() || !(dt > 0)) return false;
    const double dy = head.y() - rest_.y();
    const double dh = std::hypot(head.x() - rest_.x(), head.z() - rest_.z());
    if (armed()) {
      if (dy > cfg_.rise && dh <= cfg_.max_horizontal) {
        up_time_ += dt;
        if (up_time_ < cfg_.settle_seconds - 1e-9) return false;
        ++count_;
        rest_ = head, rest_time_ = up_time_ = 0;  // a new rest may start up here
        return true;
      }
      up_time_ = 0;
      // on the way up (getting up need not be "still"), or resting on: the rest is kept
      if (dy >= -cfg_.rest_band && dh <= cfg_.max_horizontal) return false;
      // lower, or moved away: a new rest starts here
      rest_ = head, rest_time_ = 0;
      return false;
    }
    if (!still || !have_rest_ || std::abs(dy) > cfg_.rest_band || dh > cfg_.max_horizontal) {
      rest_ = head, rest_time_ = 0, have_rest_ = true;
      return false;
    }
    rest_time_ += dt;
    return false;
  }

  StandUpConfig cfg_{};
  Eigen::Vector3d rest_ = Eigen::Vector3d::Zero();
  bool have_rest_ = false;
  double rest_time_ = 0;  // s still near rest_
  double up_time_ = 0;    // s up in a row
  long long count_ = 0;
  int unheld_ = 0;        // frames left of unheld_seconds
};

}  // namespace sparsebody::trackers
