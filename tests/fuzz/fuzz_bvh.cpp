// BVH reader: any byte string either parses (and every frame's world pose, and the tracker
// synthesis the demo runs on it, then work) or raises one LoadError naming the line.
#include <cstdint>
#include <sstream>
#include <string>

#include "sparsebody/core/error.hpp"
#include "sparsebody/pose/joint_map.hpp"
#include "sparsebody/recordings/bvh.hpp"
#include "sparsebody/recordings/tracker_synthesis.hpp"

#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    const auto clip = sparsebody::recordings::parse_bvh(in, "fuzz.bvh");
    sparsebody::pose::BodyPose tmp;
    tmp.resize(clip.skeleton.size());
    sparsebody::pose::Vec3Vector tr(static_cast<std::size_t>(clip.skeleton.size()));
    sparsebody::pose::WorldPose w;
    w.resize(clip.skeleton.size());
    for (int f = 0; f < clip.frames; ++f) clip.world_pose(f, tmp, tr, w);
    const auto map = sparsebody::pose::JointMap::from_names(clip.skeleton, "fuzz.bvh");
    const double units = sparsebody::recordings::guess_units(clip.skeleton, map);
    const auto t = sparsebody::recordings::synthesize_trackers(clip, map, units);
    sparsebody_fuzz::consume(t.floor);
  } catch (const sparsebody::LoadError& e) {
    sparsebody_fuzz::check_message(e.what());
  }
  return 0;
}
