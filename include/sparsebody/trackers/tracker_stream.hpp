// The tracker side of every pipeline's front end: frames at any rate in, model-rate ticks out
// (Resampler: interpolated, a time gap flagged), and each tick's bad input made defined
// (TrackerSanitizer, with the model period as its dt). A pipeline pushes frames through push() and
// sanitises the ticks it receives in its step (a step may also be fed ticks directly by a caller
// that resamples itself, e.g. the physics mode feeding its direct-mode pipeline).
// No allocation, no exception.
#pragma once
#include <utility>

#include "sparsebody/trackers/controller_swap.hpp"
#include "sparsebody/trackers/resampler.hpp"
#include "sparsebody/trackers/sanitizer.hpp"

namespace sparsebody::trackers {

class TrackerStream {
 public:
  explicit TrackerStream(double fps = 30.0, SanitizerConfig cfg = {}, double max_gap = 0.25)
      : resampler_(fps, max_gap), sanitizer_(cfg), recenter_(cfg.recenter, cfg.quat_tolerance),
        swap_(cfg.controller_swap, cfg.quat_tolerance) {}

  // Calls on_tick(const TrackerFrame& tick, bool gap) for every model tick up to f.time; gap: the
  // clock restarted at this tick (time jump or the first frame after one, a recentred tracking
  // space: trackers/recenter.hpp, or controllers found swapped: trackers/controller_swap.hpp).
  // Returns the tick count. The frame's controllers are exchanged first when controllers_swapped().
  template <class OnTick>
  int push(const TrackerFrame& in, OnTick&& on_tick) noexcept {
    TrackerFrame f = in;
    const bool swap = swap_.push(in, head_offset_);
    swap_.apply(f);
    if (recenter_.push(f) || swap) {  // no tick between the two worlds; the sanitizer takes the new poses
      resampler_.break_clock();
      sanitizer_.reset();
    }
    return resampler_.push(f, std::forward<OnTick>(on_tick));
  }
  int recentres() const noexcept { return recenter_.count(); }
  // Times the controllers' roles were exchanged, and whether they are now.
  int controller_swaps() const noexcept { return swap_.count(); }
  bool controllers_swapped() const noexcept { return swap_.swapped(); }
  // The calibration's headset orientation offset o_head, which says where the body faces (the
  // swap detector's heading); the OpenXR half turn until a pipeline sets its own.
  void set_head_offset(const Eigen::Quaterniond& o) noexcept { head_offset_ = o; }

  // One model tick, sanitised with dt = the model period.
  const SanitizedFrame& sanitize(const TrackerFrame& tick) noexcept { return sanitizer_.process(tick, resampler_.period()); }

  // The tracking space moved under a pipeline fed ticks by a caller that resamples itself (the
  // physics mode's direct pipeline): what push() does to the sanitizer on a recentre.
  void restart_sanitizer() noexcept { sanitizer_.reset(); }

  void reset() noexcept {
    sanitizer_.reset();
    resampler_.reset();
    recenter_.reset();
    swap_.reset();  // the controllers' roles too: a reset stream runs like a new one
  }

  double period() const noexcept { return resampler_.period(); }
  int max_ticks_per_push() const noexcept { return resampler_.max_ticks_per_push(); }
  const SanitizedFrame& last_sanitized() const noexcept { return sanitizer_.last(); }

 private:
  Resampler resampler_;
  TrackerSanitizer sanitizer_;
  RecenterDetector recenter_;
  ControllerSwapDetector swap_;
  Eigen::Quaterniond head_offset_ = ControllerSwapDetector::openxr_head_offset();
};

}  // namespace sparsebody::trackers
