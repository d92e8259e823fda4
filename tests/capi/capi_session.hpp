// The input both sides of the C API tests stream: a device-realistic headset session synthesised
// from a mocap clip (72 Hz, device offsets, per-session perturbation, timing jitter, short tracker
// losses), the clip's frame at 8.3 s held 2.5 s (as in tests/calibration) so that the automatic
// calibration finds a standing window; and the conversion from the C++ frame type to the C one.
#pragma once
#include <string>
#include <vector>

#include "sparsebody/c/sparsebody.h"
#include "sparsebody/recordings/bvh.hpp"
#include "sparsebody/recordings/tracker_synthesis.hpp"

namespace capi_test {

inline std::vector<sparsebody::trackers::TrackerFrame> device_session(const std::string& bvh) {
  namespace r = sparsebody::recordings;
  r::BvhClip clip = r::with_held_frame(r::read_bvh(bvh), 8.3, 2.5);
  const auto map = sparsebody::pose::JointMap::from_names(clip.skeleton, bvh);
  const double units = r::guess_units(clip.skeleton, map);
  r::DeviceSynthesis d;
  d.rate = 72;
  d.perturb = true;
  d.seed = 7;
  d.timing_jitter = 0.002;
  d.losses_per_second = 0.2;
  return r::synthesize_device_trackers(clip, map, units, d).frames;
}

// The shipped weights (examples/weights under `dir`) of a LoBSTr or Neural3Points pipeline kind, in
// `storage` (sb_storage); NULL when they do not load.
inline sb_weights* shipped_weights(const std::string& dir, int kind, int storage) {
  const bool lobstr = kind == SB_PIPELINE_LOBSTR;
  const std::string path = dir + (lobstr ? "/lobstr_compact.weights.json" : "/n3p");
  sb_weights* w = nullptr;
  sb_weights_load_storage(lobstr ? SB_MODEL_LOBSTR : SB_MODEL_N3P, path.c_str(), storage, &w);
  return w;
}

inline sb_tracker_frame to_c(const sparsebody::trackers::TrackerFrame& f) {
  sb_tracker_frame c{};
  c.struct_size = sizeof c;
  c.time = f.time;
  for (int k = 0; k < SB_TRACKER_COUNT; ++k) {
    const auto& p = f.pose[k];
    c.pose[k].orientation = {p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w};
    c.pose[k].position = {p.position.x, p.position.y, p.position.z};
    if (f.valid[k]) c.valid |= 1u << k;
  }
  return c;
}

}  // namespace capi_test
