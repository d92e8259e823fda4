#include "demo_input.hpp"

#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

#include "sparsebody/recordings/tracker_csv.hpp"
#include "sparsebody/recordings/tracker_synthesis.hpp"

using namespace sparsebody;

namespace demo {
namespace {
bool ends_with(const std::string& s, const char* e) {
  const std::size_t n = std::strlen(e);
  return s.size() >= n && s.compare(s.size() - n, n, e) == 0;
}

void read_bvh(const Options& o, Input& in) {
  in.clip = recordings::read_bvh(o.input);
  const pose::JointMap map = pose::JointMap::from_names(in.clip.skeleton, o.input);
  const double units = recordings::guess_units(in.clip.skeleton, map);
  recordings::SyntheticTrackers syn = recordings::synthesize_trackers(in.clip, map, units);
  in.frames = std::move(syn.frames);
  in.leg = syn.leg;
  in.truth.init(in.clip, map, units, syn.floor);
  in.fps = 1.0 / in.clip.frame_time;
  std::printf("input   %s: %d frames at %.1f fps, %d joints, units %.4g m, leg %.3f m\n", o.input.c_str(), in.clip.frames, in.fps,
              in.clip.skeleton.size(), units, syn.leg);
}

void read_csv(const Options& o, Input& in) {
  in.frames = recordings::read_tracker_csv(o.input);
  if (in.frames.empty()) throw std::runtime_error(o.input + ": no frames");
  in.fps = in.frames.size() > 1 ? (in.frames.size() - 1) / (in.frames.back().time - in.frames.front().time) : 30;
  std::printf("input   %s: %zu tracker frames (~%.1f fps)\n", o.input.c_str(), in.frames.size(), in.fps);
}

void write_trackers(const Options& o, const Input& in) {
  auto xr = in.frames;
  if (in.have_truth) recordings::to_openxr_convention(xr);
  recordings::write_tracker_csv(o.trackers_out, xr,
                                in.have_truth ? "synthesised from " + o.input + "; T-pose calibration frame 0" : "copy of " + o.input);
  std::printf("wrote   %s (%s trackers, OpenXR convention)\n", o.trackers_out.c_str(), in.have_truth ? "synthesised" : "input");
}
}  // namespace

void Truth::init(const recordings::BvhClip& c, const pose::JointMap& m, double u, double f) {
  clip = &c, map = m, units = u, floor = f;
  tmp.resize(c.skeleton.size());
  tr.resize(static_cast<std::size_t>(c.skeleton.size()));
  w.resize(c.skeleton.size());
}

void Truth::at(int frame) {
  clip->world_pose(frame, tmp, tr, w, units);
  for (auto& p : w.position) p.y() -= floor;
}

void read_input(const Options& o, Input& in) {
  in.have_truth = ends_with(o.input, ".bvh") || ends_with(o.input, ".BVH");
  if (in.have_truth) read_bvh(o, in);
  else read_csv(o, in);
  constexpr int kPelvis = static_cast<int>(trackers::Tracker::Pelvis);
  if (o.no_pelvis)
    for (auto& f : in.frames) f.valid[kPelvis] = false;
  for (const auto& f : in.frames) in.pelvis = in.pelvis || f.valid[kPelvis];
  if (!o.trackers_out.empty()) write_trackers(o, in);
}

}  // namespace demo
