// The soak run's clips: every BVH file of a folder (e.g. the unpacked validation split), trackers
// synthesised as the demo does (metres, floor at y = 0).
#pragma once
#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "soak_stream.hpp"
#include "sparsebody/core/error.hpp"
#include "sparsebody/recordings/bvh.hpp"
#include "sparsebody/recordings/tracker_synthesis.hpp"

namespace soak {

// `leg` receives the clips' mean leg length (m), to size them to a pipeline's skeleton.
inline std::vector<Clip> load_clips(const std::string& dir, double& leg) {
  namespace fs = std::filesystem;
  namespace rec = sparsebody::recordings;
  if (!fs::is_directory(dir)) throw sparsebody::LoadError(dir, "not a folder of BVH clips");
  std::vector<std::string> paths;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file() && (e.path().extension() == ".bvh" || e.path().extension() == ".BVH")) paths.push_back(e.path().string());
  std::sort(paths.begin(), paths.end());
  if (paths.empty()) throw sparsebody::LoadError(dir, "no .bvh files");
  std::vector<Clip> clips;
  double leg_sum = 0;
  for (const auto& p : paths) {
    const rec::BvhClip bvh = rec::read_bvh(p);
    if (bvh.frames < 2) continue;
    const auto map = sparsebody::pose::JointMap::from_names(bvh.skeleton, p);
    rec::SyntheticTrackers syn = rec::synthesize_trackers(bvh, map, rec::guess_units(bvh.skeleton, map));
    leg_sum += syn.leg;
    clips.push_back({p, std::move(syn.frames), bvh.frame_time});
  }
  if (clips.empty()) throw sparsebody::LoadError(dir, "no clip with 2 or more frames");
  leg = leg_sum / clips.size();
  return clips;
}

}  // namespace soak
