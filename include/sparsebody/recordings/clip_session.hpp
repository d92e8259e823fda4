// A BVH clip read as a tracker session: the one path from a mocap file to the tracker frames that
// drive a pipeline, shared by the demo (examples/demo_input.cpp), the Python module's read_input and
// demo_metrics (weights_tool/native/module.cpp), so that the same file with the same options gives
// the same frames everywhere.
//   read the clip -> optionally hold a frame as a standing window first -> joint roles from the
//   names -> turn a Z-up world to +Y -> guess the file's units -> trackers at the joints, or the
//   device stream a headset session of the motion would record (72 Hz, eye point, grips, OpenXR
//   orientations; with a seed, that user's own offsets, 2 ms jitter and short losses).
#pragma once
#include <string>
#include <utility>

#include "sparsebody/recordings/bvh.hpp"
#include "sparsebody/recordings/bvh_up_axis.hpp"
#include "sparsebody/recordings/tracker_synthesis.hpp"

namespace sparsebody::recordings {

struct ClipSessionOptions {
  bool devices = false;       // the device stream instead of trackers at the joints
  unsigned device_seed = 0;   // > 0: a perturbed session drawn from this seed (implies devices)
  double devices_stand = -1;  // >= 0 s: the clip's frame at this time held for `stand_hold` first (implies devices)
  double stand_hold = 2.5;    // s
  double device_rate = 72;    // Hz of the device stream
};

struct ClipSession {
  BvhClip clip;               // with world_turn set when the file is not Y-up
  pose::JointMap map;
  UpAxis up;
  double units = 1;           // metres per file unit
  bool devices = false;       // the options' devices after the implications above
  double device_rate = 72;    // Hz
  SyntheticTrackers trackers; // frames, floor (m, subtracted from y), leg (m)
  double fps() const noexcept { return devices ? device_rate : 1.0 / clip.frame_time; }
};

// Throws std::runtime_error naming the file (recordings::read_bvh's and JointMap's errors).
inline ClipSession read_clip_session(const std::string& path, const ClipSessionOptions& o = {}) {
  ClipSession s;
  s.devices = o.devices || o.device_seed > 0 || o.devices_stand >= 0;
  s.device_rate = o.device_rate;
  s.clip = read_bvh(path);
  if (o.devices_stand >= 0) s.clip = with_held_frame(std::move(s.clip), o.devices_stand, o.stand_hold);
  s.map = pose::JointMap::from_names(s.clip.skeleton, path);
  s.up = make_y_up(s.clip, s.map);
  s.units = guess_units(s.clip.skeleton, s.map);
  if (s.devices) {
    DeviceSynthesis d;
    d.rate = o.device_rate;
    if (o.device_seed > 0) {
      d.perturb = true;
      d.seed = o.device_seed;
      d.timing_jitter = 0.002;
      d.losses_per_second = 0.2;
    }
    s.trackers = synthesize_device_trackers(s.clip, s.map, s.units, d);
  } else {
    s.trackers = synthesize_trackers(s.clip, s.map, s.units);
  }
  return s;
}

}  // namespace sparsebody::recordings
