// The tracker side of every pipeline's front end: frames at any rate in, model-rate ticks out
// (Resampler: interpolated, a time gap flagged), and each tick's bad input made defined
// (TrackerSanitizer, with the model period as its dt). A pipeline pushes frames through push() and
// sanitises the ticks it receives in its step (a step may also be fed ticks directly by a caller
// that resamples itself, e.g. the physics mode feeding its direct-mode pipeline).
// No allocation, no exception.
#pragma once
#include <utility>

#include "sparsebody/trackers/resampler.hpp"
#include "sparsebody/trackers/sanitizer.hpp"

namespace sparsebody::trackers {

class TrackerStream {
 public:
  explicit TrackerStream(double fps = 30.0, SanitizerConfig cfg = {}, double max_gap = 0.25)
      : resampler_(fps, max_gap), sanitizer_(cfg), recenter_(cfg.recenter, cfg.quat_tolerance) {}

  // Calls on_tick(const TrackerFrame& tick, bool gap) for every model tick up to f.time; gap: the
  // clock restarted at this tick (time jump or the first frame after one, or a recentred tracking
  // space: trackers/recenter.hpp). Returns the tick count.
  template <class OnTick>
  int push(const TrackerFrame& f, OnTick&& on_tick) noexcept {
    if (recenter_.push(f)) {  // no tick between the two worlds; the sanitizer takes the new poses
      resampler_.break_clock();
      sanitizer_.reset();
    }
    return resampler_.push(f, std::forward<OnTick>(on_tick));
  }
  int recentres() const noexcept { return recenter_.count(); }

  // One model tick, sanitised with dt = the model period.
  const SanitizedFrame& sanitize(const TrackerFrame& tick) noexcept { return sanitizer_.process(tick, resampler_.period()); }

  // The tracking space moved under a pipeline fed ticks by a caller that resamples itself (the
  // physics mode's direct pipeline): what push() does to the sanitizer on a recentre.
  void restart_sanitizer() noexcept { sanitizer_.reset(); }

  void reset() noexcept {
    sanitizer_.reset();
    resampler_.reset();
    recenter_.reset();
  }

  double period() const noexcept { return resampler_.period(); }
  const SanitizedFrame& last_sanitized() const noexcept { return sanitizer_.last(); }

 private:
  Resampler resampler_;
  TrackerSanitizer sanitizer_;
  RecenterDetector recenter_;
};

}  // namespace sparsebody::trackers
