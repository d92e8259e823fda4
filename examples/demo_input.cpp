#include "demo_input.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

#include "sparsebody/recordings/clip_session.hpp"
#include "sparsebody/recordings/tracker_csv.hpp"

using namespace sparsebody;

namespace demo {
namespace {
bool ends_with(const std::string& s, const char* e) {
  const std::size_t n = std::strlen(e);
  return s.size() >= n && s.compare(s.size() - n, n, e) == 0;
}

void read_bvh(const Options& o, Input& in) {
  recordings::ClipSessionOptions co;
  co.devices = o.devices, co.device_seed = o.device_seed, co.devices_stand = o.devices_stand;
  recordings::ClipSession cs = recordings::read_clip_session(o.input, co);
  if (o.devices_stand >= 0)
    std::printf("stand   the clip's frame at %.2f s held for 2.5 s (--devices-stand): a standing window\n", o.devices_stand);
  in.clip = std::move(cs.clip);
  const recordings::SyntheticTrackers& syn = cs.trackers;
  const recordings::UpAxis& up = cs.up;
  const double units = cs.units;
  in.frames = std::move(cs.trackers.frames);
  in.at_joints = !cs.devices;
  in.leg = syn.leg;
  in.truth.init(in.clip, cs.map, units, syn.floor);
  in.fps = cs.fps();
  std::printf("input   %s: %d frames at %.1f fps, %d joints, units %.4g m, leg %.3f m\n", o.input.c_str(), in.clip.frames,
              1.0 / in.clip.frame_time, in.clip.skeleton.size(), units, syn.leg);
  if (up.turned)
    std::printf("up      the file's world is %c%c-up (hips -> head nearest that axis on %.0f %% of frames): turned to +Y\n",
                up.sign > 0 ? '+' : '-', up.name(), 100.0 * up.share);
  if (o.devices)
    std::printf("devices %zu device frames at 72 Hz: headset at the eyes, grips off the wrists, OpenXR orientations%s\n",
                in.frames.size(), o.device_seed > 0 ? ", per-session perturbation, 2 ms jitter, short losses" : "");
}

void read_csv(const Options& o, Input& in) {
  recordings::TrackerCsvInfo info;
  in.frames = recordings::read_tracker_csv(o.input, &info);
  if (in.frames.empty()) throw std::runtime_error(o.input + ": no frames");
  in.fps = in.frames.size() > 1 ? (in.frames.size() - 1) / (in.frames.back().time - in.frames.front().time) : 30;
  std::printf("input   %s: %zu tracker frames (~%.1f fps)\n", o.input.c_str(), in.frames.size(), in.fps);
  if (info.to_seconds != 1.0)
    std::printf("time    the time column is in %s (median frame interval %.2f ms): converted to seconds\n", info.time_unit,
                1e3 * info.median_interval);
}

void write_trackers(const Options& o, const Input& in) {
  auto xr = in.frames;
  if (in.at_joints) recordings::to_openxr_convention(xr);
  const std::string what = !in.have_truth ? "copy of " + o.input
                           : in.at_joints ? "synthesised from " + o.input + " at the joints; T-pose calibration frame 0"
                                          : "device-realistic session synthesised from " + o.input +
                                                ": 72 Hz, headset eye offset, controller grip offsets, no T-pose, floor y = 0";
  recordings::write_tracker_csv(o.trackers_out, xr, what);
  std::printf("wrote   %s (%s trackers, OpenXR convention)\n", o.trackers_out.c_str(),
              !in.have_truth ? "input" : in.at_joints ? "synthesised" : "device-realistic");
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

long frame_at(const Input& in, double t) {
  const auto it = std::lower_bound(in.frames.begin(), in.frames.end(), t,
                                   [](const trackers::TrackerFrame& f, double x) { return f.time < x; });
  long i = static_cast<long>(it - in.frames.begin());
  if (i > 0 && (i == static_cast<long>(in.frames.size()) || std::abs(in.frames[i - 1].time - t) <= std::abs(in.frames[i].time - t))) --i;
  return i;
}

void read_input(const Options& o, Input& in) {
  in.have_truth = ends_with(o.input, ".bvh") || ends_with(o.input, ".BVH");
  if (in.have_truth) read_bvh(o, in);
  else read_csv(o, in);
  if (!in.have_truth && o.devices) std::printf("note    --devices synthesises trackers from a BVH clip; a CSV is used as recorded\n");
  constexpr int kPelvis = static_cast<int>(trackers::Tracker::Pelvis);
  if (o.no_pelvis)
    for (auto& f : in.frames) f.valid[kPelvis] = false;
  for (const auto& f : in.frames) in.pelvis = in.pelvis || f.valid[kPelvis];
  if (!o.trackers_out.empty()) write_trackers(o, in);
}

}  // namespace demo
