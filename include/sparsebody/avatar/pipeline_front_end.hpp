// The front end the pipelines share (CRTP): tracker frames at any rate in (push), one
// Derived::step(tick, gap) per model tick (trackers/tracker_stream.hpp), and the guarded output
// pose (pose/pose_output.hpp): pose(), world(), has_output(), frames().
//
// Derived provides `void step(const trackers::TrackerFrame& tick, bool gap) noexcept`, which
// sanitises the tick (stream_.sanitize), counts it (++frames_), builds its frame in out_.pose() /
// out_.world() and commits it (out_.commit(): a frame that is not finite keeps the last one). Its
// constructor calls start_front_end once its model rate and skeleton are known, its reset()
// calls reset_front_end(). It also provides `Eigen::Quaterniond head_offset() const` (its
// calibration's o_head, the heading the controller-swap check uses) and
// `void swap_controller_calibration() noexcept` (the stream found the controllers in the other
// hands and exchanges them from this tick on: the calibration's controller offsets follow their
// devices), called before the first step of the new roles.
#pragma once
#include <utility>

#include "sparsebody/pose/pose_output.hpp"
#include "sparsebody/trackers/tracker_stream.hpp"

namespace sparsebody::avatar {

template <class Derived>
class PipelineFrontEnd {
 public:
  // Feeds one input frame at any rate; runs one model step per model tick it completes.
  // Returns the number of steps run (0 when the frame falls between ticks).
  int push(const trackers::TrackerFrame& f) noexcept {
    stream_.set_head_offset(self().head_offset());
    return stream_.push(f, [this](const trackers::TrackerFrame& tick, bool gap) {
      follow_controller_roles();
      self().step(tick, gap);
    });
  }
  // The same, calling after(tick, gap) after each step: for a pipeline that runs on this one's
  // output (the physics mode on direct mode) and so shares its ticks.
  template <class After>
  int push(const trackers::TrackerFrame& f, After&& after) noexcept {
    stream_.set_head_offset(self().head_offset());
    return stream_.push(f, [this, &after](const trackers::TrackerFrame& tick, bool gap) {
      follow_controller_roles();
      self().step(tick, gap);
      after(tick, gap);
    });
  }

  // push(f) in two halves, for a batch of users whose ticks step together (avatar/batch_users.hpp):
  // push_ticks(f, keep) feeds f through the stream and hands each tick it completes to
  // keep(tick, gap) instead of stepping it (at most tracker_stream().max_ticks_per_push()); the
  // batch then steps those ticks in order, calling before_tick() before each, as push(f) would.
  template <class Keep>
  int push_ticks(const trackers::TrackerFrame& f, Keep&& keep) noexcept {
    stream_.set_head_offset(self().head_offset());
    return stream_.push(f, std::forward<Keep>(keep));
  }
  void before_tick() noexcept { follow_controller_roles(); }

  // The pose on the pipeline's skeleton; valid when has_output().
  const pose::BodyPose& pose() const noexcept { return out_.pose(); }
  const pose::WorldPose& world() const noexcept { return out_.world(); }
  bool has_output() const noexcept { return out_.has_output(); }
  long long frames() const noexcept { return frames_; }  // model frames stepped since the last reset
  // The resampler and sanitizer (last_sanitized().reset: the last tick restarted the model).
  const trackers::TrackerStream& tracker_stream() const noexcept { return stream_; }
  // Recentred tracking spaces found in the input so far (trackers/recenter.hpp: each one restarted
  // the model at that frame).
  int recentres() const noexcept { return stream_.recentres(); }
  // Times the controllers were found in the other hands and exchanged (trackers/controller_swap.hpp),
  // and whether they are exchanged now.
  int controller_swaps() const noexcept { return stream_.controller_swaps(); }
  bool controllers_swapped() const noexcept { return stream_.controllers_swapped(); }

 protected:
  PipelineFrontEnd() = default;

  void start_front_end(double fps, const trackers::SanitizerConfig& cfg, int joints) {
    stream_ = trackers::TrackerStream(fps, cfg);
    swaps_seen_ = 0;
    out_.resize(joints);
  }
  void reset_front_end() noexcept {
    // The stream forgets the controllers' roles (a reset instance runs like a new one), so a
    // calibration that followed an exchange (an explicit one survives reset) goes back with them.
    if (stream_.controllers_swapped()) self().swap_controller_calibration();
    stream_.reset();
    swaps_seen_ = stream_.controller_swaps();
    out_.reset();
    frames_ = 0;
  }

  trackers::TrackerStream stream_;
  pose::PoseOutput out_;
  long long frames_ = 0;
  int swaps_seen_ = 0;  // stream_.controller_swaps() the calibration has followed

 private:
  Derived& self() noexcept { return static_cast<Derived&>(*this); }
  void follow_controller_roles() noexcept {
    if (stream_.controller_swaps() == swaps_seen_) return;
    swaps_seen_ = stream_.controller_swaps();
    self().swap_controller_calibration();
  }
};

}  // namespace sparsebody::avatar
