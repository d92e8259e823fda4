// The Python module's frame loop, free of pybind11 so a doctest can count its allocations
// (tests/pymod/test_batch_alloc.cpp): a batch of tracker frames (flat arrays, as numpy hands them
// over) pushed through any kinematic or physics pipeline, one output row per input frame written
// into caller-owned arrays. Nothing here allocates, throws or locks once the arrays exist.
#pragma once
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <type_traits>

#include "sparsebody/features/calibration_report.hpp"
#include "sparsebody/trackers/types.hpp"

namespace sparsebody::pymod {

// T input frames of K trackers (3: head, left, right; 4: + pelvis). Row-major:
// position [T,K,3] metres, orientation [T,K,4] quaternions (x, y, z, w) as XrPosef, valid [T,K].
struct FrameBatch {
  long T = 0;
  int K = 4;
  const double* time = nullptr;
  const float* position = nullptr;
  const float* orientation = nullptr;
  const bool* valid = nullptr;
};

// Per input frame: the pipeline's state after that frame was pushed. J joints of the pipeline's
// skeleton. Any pointer may be null (not wanted). Where has_output is false, poses are NaN.
struct OutputBatch {
  double* position = nullptr;        // [T,J,3] world, the user's size (pipeline world x user_scale)
  double* world_rotation = nullptr;  // [T,J,4] world rotations (x, y, z, w)
  double* rotation = nullptr;        // [T,J,4] local rotations (x, y, z, w); [.,0] is the root's world rotation
  double* root = nullptr;            // [T,3] root position, standard scale (the BVH writer's input)
  bool* contact = nullptr;           // [T,2] left, right
  double* contact_probability = nullptr;  // [T,2] the network's (physics: the direct mode's prediction)
  bool* foot_locked = nullptr;       // [T,2] kinematic: FootLock engaged; physics: the direct reference's
  std::int32_t* steps = nullptr;     // [T] model steps this frame ran (0: between ticks)
  bool* has_output = nullptr;        // [T]
  bool* standing_still = nullptr;    // [T]
  std::int8_t* calibration = nullptr;  // [T] CalibrationStatus: 0 default body, 1 calibrated, 2 refused
  double* user_scale = nullptr;      // [T]
  double* time = nullptr;            // [T] input time of the pose shown (kinematic: last tick; physics: output_time)
  double* residual_force = nullptr;  // [T] physics: mean residual force over this frame's substeps (N); NaN if none
  double* residual_torque = nullptr; // [T] physics: the same, torque (N m)
  std::int64_t* falls = nullptr;     // [T] physics: fall resets so far
};

// The first problem of a batch as one line in `msg` (empty: none). Checked before the run so a bad
// batch changes no state. prev_time: the last time already pushed (-inf at start).
inline bool check_batch(const FrameBatch& b, double prev_time, char* msg, std::size_t n) noexcept {
  msg[0] = '\0';
  double prev = prev_time;
  for (long t = 0; t < b.T; ++t) {
    const double time = b.time[t];
    if (!std::isfinite(time)) {
      std::snprintf(msg, n, "frame %ld: timestamp is %g (must be finite)", t, time);
      return false;
    }
    if (!(time > prev)) {
      std::snprintf(msg, n, "frame %ld: timestamp %.9g does not increase (previous %.9g); strict=False lets the pipeline restart on it",
                    t, time, prev);
      return false;
    }
    prev = time;
    for (int k = 0; k < b.K; ++k) {
      if (!b.valid[t * b.K + k]) continue;
      const float* p = b.position + (t * b.K + k) * 3;
      const float* q = b.orientation + (t * b.K + k) * 4;
      for (int i = 0; i < 7; ++i) {
        const float v = i < 3 ? p[i] : q[i - 3];
        if (!std::isfinite(v)) {
          std::snprintf(msg, n, "frame %ld, tracker %d (%s): %s is %g in a pose marked valid (mark lost trackers invalid, or strict=False)",
                        t, k, trackers::tracker_name(k), i < 3 ? "position" : "orientation", static_cast<double>(v));
          return false;
        }
      }
    }
  }
  return true;
}

namespace detail {
template <class P, class = void>
struct is_physics : std::false_type {};
template <class P>
struct is_physics<P, std::void_t<decltype(std::declval<const P&>().residual_stats())>> : std::true_type {};

inline trackers::TrackerFrame frame_at(const FrameBatch& b, long t) noexcept {
  trackers::TrackerFrame f;
  f.time = b.time[t];
  for (int k = 0; k < trackers::kTrackerCount; ++k) {
    if (k >= b.K) { f.valid[k] = false; continue; }
    const float* p = b.position + (t * b.K + k) * 3;
    const float* q = b.orientation + (t * b.K + k) * 4;
    f.pose[k].position = {p[0], p[1], p[2]};
    f.pose[k].orientation = {q[0], q[1], q[2], q[3]};
    f.valid[k] = b.valid[t * b.K + k];
  }
  return f;
}

inline void put_quat(double* o, const Eigen::Quaterniond& q) noexcept {
  o[0] = q.x(), o[1] = q.y(), o[2] = q.z(), o[3] = q.w();
}
}  // namespace detail

// Pushes every frame of `in` into `pipe` (any sparsebody pipeline with the shared front end) and
// writes row t of `out` after frame t. last_tick: the time of the newest model tick (kept between
// batches by the caller, NaN before the first).
template <class Pipeline>
void run_batch(Pipeline& pipe, const FrameBatch& in, const OutputBatch& out, double& last_tick) noexcept {
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  constexpr bool physics = detail::is_physics<Pipeline>::value;
  const int J = pipe.skeleton().size();
  for (long t = 0; t < in.T; ++t) {
    const trackers::TrackerFrame f = detail::frame_at(in, t);
    double force0 = 0, torque0 = 0;
    long long sub0 = 0;
    if constexpr (physics) {
      force0 = pipe.residual_stats().force_sum, torque0 = pipe.residual_stats().torque_sum, sub0 = pipe.residual_stats().steps;
    }
    const int k = pipe.push(f, [&last_tick](const trackers::TrackerFrame& tick, bool) { last_tick = tick.time; });
    const bool has = pipe.has_output();
    const double user = pipe.user_scale();
    if (out.steps) out.steps[t] = k;
    if (out.has_output) out.has_output[t] = has;
    if (out.user_scale) out.user_scale[t] = user;
    if (out.calibration) out.calibration[t] = static_cast<std::int8_t>(pipe.calibration_report().status);
    const auto& pose = pipe.pose();
    const auto& world = pipe.world();
    for (int j = 0; j < J; ++j) {
      const std::size_t r = static_cast<std::size_t>(t) * J + j;
      for (int i = 0; i < 3; ++i)
        if (out.position) out.position[r * 3 + i] = has ? world.position[j][i] * user : nan;
      if (out.rotation) {
        if (has) detail::put_quat(out.rotation + r * 4, pose.local[j]);
        else for (int i = 0; i < 4; ++i) out.rotation[r * 4 + i] = nan;
      }
      if (out.world_rotation) {
        if (has) detail::put_quat(out.world_rotation + r * 4, world.rotation[j]);
        else for (int i = 0; i < 4; ++i) out.world_rotation[r * 4 + i] = nan;
      }
    }
    if (out.root)
      for (int i = 0; i < 3; ++i) out.root[t * 3 + i] = has ? pose.root_position[i] : nan;
    for (int s = 0; s < 2; ++s) {
      if (out.contact) out.contact[t * 2 + s] = pipe.contact(s);
      if constexpr (physics) {
        if (out.contact_probability) out.contact_probability[t * 2 + s] = pipe.direct().contact_probability(s);
        if (out.foot_locked) out.foot_locked[t * 2 + s] = pipe.direct().foot_locked(s);
      } else {
        if (out.contact_probability) out.contact_probability[t * 2 + s] = pipe.contact_probability(s);
        if (out.foot_locked) out.foot_locked[t * 2 + s] = pipe.foot_locked(s);
      }
    }
    if constexpr (physics) {
      if (out.standing_still) out.standing_still[t] = pipe.direct().standing_still();
      if (out.time) out.time[t] = has ? pipe.output_time() : nan;
      const auto& st = pipe.residual_stats();
      const long long n = st.steps - sub0;
      if (out.residual_force) out.residual_force[t] = n > 0 ? (st.force_sum - force0) / n : nan;
      if (out.residual_torque) out.residual_torque[t] = n > 0 ? (st.torque_sum - torque0) / n : nan;
      if (out.falls) out.falls[t] = pipe.falls();
    } else {
      if (out.standing_still) out.standing_still[t] = pipe.standing_still();
      if (out.time) out.time[t] = has ? last_tick : nan;
      if (out.residual_force) out.residual_force[t] = nan;
      if (out.residual_torque) out.residual_torque[t] = nan;
      if (out.falls) out.falls[t] = 0;
    }
  }
}

}  // namespace sparsebody::pymod
