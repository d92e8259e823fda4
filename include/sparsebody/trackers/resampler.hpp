// Resamples tracker frames arriving at any rate (72-120 Hz headsets, 30-120 Hz files) to the
// model's fixed rate: every tick k/fps between two input frames gets positions interpolated
// linearly and orientations by slerp. A tracker valid on only one side takes that side's pose when
// it is the nearer one, else it is invalid at that tick. A time gap longer than `max_gap` (or time
// going backwards) restarts the tick clock at the new frame and flags the tick as a reset.
#pragma once
#include "sparsebody/trackers/types.hpp"

namespace sparsebody::trackers {

class Resampler {
 public:
  explicit Resampler(double fps = 30.0, double max_gap = 0.25) : period_(1.0 / fps), max_gap_(max_gap) {}

  double period() const noexcept { return period_; }
  // The most ticks one push() can emit: those in one gap of at most max_gap, or 1 on a restart.
  int max_ticks_per_push() const noexcept { return static_cast<int>(max_gap_ / period_ + 1e-6) + 1; }
  void reset() noexcept { started_ = false; }
  // The next frame restarts the tick clock and is flagged as a reset, as after a time gap (the
  // frames before it are in another world: trackers/recenter.hpp).
  void break_clock() noexcept { broken_ = started_; }

  // Calls emit(const TrackerFrame& tick, bool reset) for every model tick up to f.time.
  // Returns the number of ticks emitted. No allocation.
  template <class Emit>
  int push(const TrackerFrame& f, Emit&& emit) {
    if (!std::isfinite(f.time)) return 0;  // a frame without a usable time is dropped
    if (!started_ || broken_ || f.time <= prev_.time - 1e-9 || f.time - prev_.time > max_gap_) {
      const bool was = started_;
      broken_ = false;
      started_ = true;
      prev_ = f;
      next_ = f.time + period_;
      emit(f, was);
      return 1;
    }
    int n = 0;
    const double span = f.time - prev_.time;
    while (next_ <= f.time + 1e-9) {
      const double a = span > 0 ? (next_ - prev_.time) / span : 1.0;
      tick_.time = next_;
      for (int k = 0; k < kTrackerCount; ++k) interpolate(k, f, a);
      emit(tick_, false);
      next_ += period_;
      ++n;
    }
    prev_ = f;
    return n;
  }

 private:
  void interpolate(int k, const TrackerFrame& f, double a) noexcept {
    const bool v0 = prev_.valid[k], v1 = f.valid[k];
    if (v0 && v1) {
      const Eigen::Vector3d p = (1 - a) * to_eigen(prev_.pose[k].position) + a * to_eigen(f.pose[k].position);
      Eigen::Quaterniond q0 = to_eigen(prev_.pose[k].orientation), q1 = to_eigen(f.pose[k].orientation);
      const Eigen::Quaterniond q = q0.normalized().slerp(a, q1.normalized());
      tick_.pose[k] = {to_xr(q), to_xr(p)};
      tick_.valid[k] = true;
    } else if (v0 && a < 0.5) {
      tick_.pose[k] = prev_.pose[k];
      tick_.valid[k] = true;
    } else if (v1 && a >= 0.5) {
      tick_.pose[k] = f.pose[k];
      tick_.valid[k] = true;
    } else {
      tick_.valid[k] = false;
    }
  }

  double period_, max_gap_;
  bool started_ = false, broken_ = false;
  double next_ = 0;
  TrackerFrame prev_{}, tick_{};
};

}  // namespace sparsebody::trackers
