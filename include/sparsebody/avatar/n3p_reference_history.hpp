// The reference frames of the Neural3Points physics mode since the last (re)start: per input frame
// n, the retargeted prediction q_ref(n) and what the simulation needs of that frame later (it
// reaches frame n kDelayFrames after it arrived, avatar/n3p_physics.hpp): the controllers'
// positions in simulation coordinates (tracker correction), the predicted contacts (stance
// support), the calibrated trackers (the policy's input) and the frame's time. A ring of N frames;
// at(n) clamps n to the frames since the start (first() .. newest()), so a finite difference or a
// target lead over the ends repeats the end frame.
// No allocation after construction.
#pragma once
#include <algorithm>
#include <array>
#include <cstddef>

#include "sparsebody/dynamics/model.hpp"
#include "sparsebody/features/n3p_tracker_input.hpp"

namespace sparsebody::avatar {

template <class S, int MB, int MD, int N = 8>
class N3PReferenceHistory {
 public:
  using VecQ = typename dynamics::Model<S, MB, MD>::VecQ;

  struct Frame {
    VecQ q;                                     // q_ref(n)
    dynamics::Vec3<S> hand[2] = {dynamics::Vec3<S>::Zero(), dynamics::Vec3<S>::Zero()};  // controllers, sim coordinates
    bool hand_present[2] = {false, false};
    double time = 0;
    double contact[2] = {1, 1};                 // predicted c_L, c_R
    features::n3p::TrackerSet trackers{};       // calibrated o (policy path)
    std::array<bool, 3> present{};              // headset, left, right controller
  };

  // Every frame's q = q0 (sized: no allocation later).
  explicit N3PReferenceHistory(const VecQ& q0 = VecQ()) {
    for (auto& f : frames_) f.q = q0;
  }

  // Starts the frames over at number n with the frame of q, the direct-mode step just taken
  // (Direct: avatar::N3PPipeline; retarget: control::N3PSimRetarget) and its time.
  template <class Direct, class Retarget>
  void start(long long n, const VecQ& q, const Direct& direct, const Retarget& retarget, double time) noexcept {
    first_ = newest_ = n;
    record(frame(n), q, direct, retarget, time);
  }
  // The next frame (newest() + 1), likewise.
  template <class Direct, class Retarget>
  void push(const VecQ& q, const Direct& direct, const Retarget& retarget, double time) noexcept {
    record(frame(++newest_), q, direct, retarget, time);
  }

  long long first() const noexcept { return first_; }
  long long newest() const noexcept { return newest_; }
  // Frame n, clamped to first() .. newest().
  const Frame& at(long long n) const noexcept { return frames_[slot(std::clamp(n, first_, newest_))]; }
  const VecQ& q(long long n) const noexcept { return at(n).q; }

 private:
  static std::size_t slot(long long n) noexcept { return static_cast<std::size_t>(((n % N) + N) % N); }
  Frame& frame(long long n) noexcept { return frames_[slot(n)]; }

  template <class Direct, class Retarget>
  static void record(Frame& h, const VecQ& q, const Direct& direct, const Retarget& retarget, double time) noexcept {
    h.q = q;
    for (int s = 0; s < 2; ++s) {
      h.hand_present[s] = direct.trackers_present()[1 + s];
      h.hand[s] = retarget.to_sim_point(direct.trackers()[1 + s].p).template cast<S>();
    }
    h.time = time;
    h.trackers = direct.trackers();
    h.present = direct.trackers_present();
    h.contact[0] = direct.contact_probability(0);
    h.contact[1] = direct.contact_probability(1);
  }

  std::array<Frame, N> frames_{};
  long long first_ = 0, newest_ = 0;
};

}  // namespace sparsebody::avatar
