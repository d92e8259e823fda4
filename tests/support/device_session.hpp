// The CMU clip 01_01 (SPARSEBODY_TEST_CLIP) as a headset session records it: its first frame held
// for 2.5 s (a standing start), then the motion, as device-realistic trackers at 72 Hz
// (recordings/tracker_synthesis.hpp). Built once per test executable.
#pragma once
#include <vector>

#include "sparsebody/recordings/bvh.hpp"
#include "sparsebody/recordings/tracker_synthesis.hpp"

namespace sparsebody_test {

inline const std::vector<sparsebody::trackers::TrackerFrame>& device_session_01_01() {
  using namespace sparsebody;
  static const std::vector<trackers::TrackerFrame> frames = [] {
    const recordings::BvhClip clip = recordings::with_held_frame(recordings::read_bvh(SPARSEBODY_TEST_CLIP), 0.0, 2.5);
    const pose::JointMap map = pose::JointMap::from_names(clip.skeleton, "01_01");
    recordings::DeviceSynthesis opt;
    opt.rate = 72;
    return recordings::synthesize_device_trackers(clip, map, recordings::guess_units(clip.skeleton, map), opt).frames;
  }();
  return frames;
}

}  // namespace sparsebody_test
