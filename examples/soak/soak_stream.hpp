// The soak run's input: validation clips joined end to end into hours of tracker frames at the
// clips' rate, with the events a long headset session has, drawn from a seeded generator:
//   dropout      one tracker invalid for 0.2-2 s                    (about every 40 s)
//   nan_burst    one tracker's position NaN for 1-10 frames           (about every 60 s)
//   gap          2 s without frames (time jumps forward)              (about every 120 s)
//   teleport     every tracker moved by up to 3 m (origin recentred)  (about every 300 s)
//   time_back    the clock steps back 1 s                             (about every 300 s)
//   recalibrate  a calibration request on an arbitrary (not T-pose) frame, then, 10 s later, the
//                proper calibration again                             (about every 600 s)
// Each clip is turned about the vertical and moved so that it starts where, and facing where, the
// previous one ended (a continuous walk), so the only discontinuities are the events.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "sparsebody/trackers/types.hpp"

namespace soak {

using sparsebody::trackers::TrackerFrame;
using sparsebody::trackers::to_eigen;
using sparsebody::trackers::to_xr;

enum Event : int { kDropout, kNanBurst, kGap, kTeleport, kTimeBack, kRecalibrate, kEventCount };
inline const char* event_name(int e) {
  static const char* n[] = {"dropout", "nan_burst", "gap", "teleport", "time_back", "recalibrate"};
  return n[e];
}

// One clip's frames (metres, floor at y = 0, body convention as the tracker synthesis gives them).
struct Clip {
  std::string name;
  std::vector<TrackerFrame> frames;
  double frame_time = 1.0 / 30;
};

struct StreamFrame {
  TrackerFrame frame;
  bool skip = false;          // part of a gap: not delivered
  int event = -1;             // an event starting at this frame
  bool recalibrate = false;   // ask for a calibration on this frame
  bool restore = false;       // restore the proper calibration on this frame
};

class Stream {
 public:
  Stream(const std::vector<Clip>& clips, std::uint64_t seed) : clips_(clips), rng_(seed) {}

  const std::vector<long long>& event_counts() const { return counts_; }
  double input_seconds() const { return t_; }

  // The next frame of the endless stream.
  StreamFrame next() {
    if (k_ >= clips_[clip_].frames.size()) start_clip();
    const Clip& c = clips_[clip_];
    StreamFrame out;
    TrackerFrame f = c.frames[k_++];
    for (auto& p : f.pose) {  // x' = R_y (x - pivot) + start, q' = R_y q
      const Eigen::Vector3d x = turn_ * (to_eigen(p.position) - pivot_) + start_;
      p.position = to_xr(Eigen::Vector3d(x.x() + teleport_[0], x.y(), x.z() + teleport_[2]));
      p.orientation = to_xr(Eigen::Quaterniond(turn_ * to_eigen(p.orientation)));
    }
    t_ += c.frame_time;
    f.time = t_ + clock_offset_;
    draw_events(out, c.frame_time);
    if (dropout_left_ > 0) { f.valid[dropout_tracker_] = false; --dropout_left_; }
    if (nan_left_ > 0) { f.pose[nan_tracker_].position.y = std::nanf(""); --nan_left_; }
    if (gap_left_ > 0) { out.skip = true; --gap_left_; }
    if (restore_in_ > 0 && --restore_in_ == 0) out.restore = true;
    last_head_ = Eigen::Vector3d(f.pose[0].position.x - teleport_[0], 0, f.pose[0].position.z - teleport_[2]);
    last_yaw_ = yaw_of(to_eigen(f.pose[0].orientation));
    out.frame = f;
    return out;
  }

 private:
  // Heading of a tracker orientation (body convention: its Z axis is forward).
  static double yaw_of(const Eigen::Quaterniond& q) {
    const Eigen::Vector3d f = q * Eigen::Vector3d::UnitZ();
    return std::atan2(f.x(), f.z());
  }

  void start_clip() {
    clip_ = std::uniform_int_distribution<std::size_t>(0, clips_.size() - 1)(rng_);
    k_ = 0;
    const auto& first = clips_[clip_].frames.front().pose[0];
    pivot_ = Eigen::Vector3d(first.position.x, 0, first.position.z);
    if (started_) {  // continue from where, and facing where, the last clip ended
      turn_ = Eigen::AngleAxisd(last_yaw_ - yaw_of(to_eigen(first.orientation)), Eigen::Vector3d::UnitY());
      start_ = last_head_;
    } else {
      start_ = pivot_;
    }
    started_ = true;
  }

  bool chance(double mean_interval, double dt) { return std::uniform_real_distribution<double>(0, 1)(rng_) < dt / mean_interval; }

  void draw_events(StreamFrame& out, double dt) {
    std::uniform_real_distribution<double> u(0, 1);
    auto start = [&](int e) { out.event = e; ++counts_[e]; };
    if (dropout_left_ == 0 && chance(40, dt)) {
      start(kDropout);
      dropout_tracker_ = static_cast<int>(u(rng_) * 4) % 4;
      dropout_left_ = static_cast<int>((0.2 + 1.8 * u(rng_)) / dt);
    } else if (nan_left_ == 0 && chance(60, dt)) {
      start(kNanBurst);
      nan_tracker_ = static_cast<int>(u(rng_) * 4) % 4;
      nan_left_ = 1 + static_cast<int>(u(rng_) * 9);
    } else if (gap_left_ == 0 && chance(120, dt)) {
      start(kGap);
      gap_left_ = static_cast<int>(2.0 / dt);
    } else if (chance(300, dt)) {
      start(kTeleport);
      teleport_[0] += 6 * (u(rng_) - 0.5);
      teleport_[2] += 6 * (u(rng_) - 0.5);
    } else if (chance(300, dt)) {
      start(kTimeBack);
      clock_offset_ -= 1.0;
    } else if (restore_in_ == 0 && chance(600, dt)) {
      start(kRecalibrate);
      out.recalibrate = true;
      restore_in_ = static_cast<int>(10.0 / dt);
    }
  }

  const std::vector<Clip>& clips_;
  std::mt19937_64 rng_;
  std::size_t clip_ = 0, k_ = static_cast<std::size_t>(-1);  // the first next() starts a clip
  bool started_ = false;
  double t_ = 0, clock_offset_ = 0;
  double teleport_[3] = {0, 0, 0};
  Eigen::Quaterniond turn_ = Eigen::Quaterniond::Identity();
  Eigen::Vector3d pivot_ = Eigen::Vector3d::Zero(), start_ = Eigen::Vector3d::Zero(), last_head_ = Eigen::Vector3d::Zero();
  double last_yaw_ = 0;
  int dropout_left_ = 0, dropout_tracker_ = 0, nan_left_ = 0, nan_tracker_ = 0, gap_left_ = 0, restore_in_ = 0;
  std::vector<long long> counts_ = std::vector<long long>(kEventCount, 0);
};

}  // namespace soak
