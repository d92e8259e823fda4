// sparsebody_demo --html: records what the run showed (avatar, trackers, ground truth, contacts) and
// writes one self-contained page (examples/viewer/viewer.html with three.js inlined) that plays it.
// Positions are kept as integer millimetres, tracker orientations as int16 quaternions: the page
// stays small (README: size of a 1-minute clip) and the recording reserves its storage up front, so
// add() does not allocate per frame (tests/viewer/test_viewer_recorder.cpp).
#pragma once
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "sparsebody/pose/body_pose.hpp"
#include "sparsebody/pose/joint_map.hpp"
#include "sparsebody/pose/skeleton.hpp"
#include "sparsebody/trackers/types.hpp"

namespace demo {

class ViewerRecorder {
 public:
  // The avatar's skeleton and roles, the ground truth's skeleton (nullptr: no ground truth) and the
  // number of frames to reserve for (more still work, they only allocate).
  void begin(const sparsebody::pose::Skeleton& avatar, const sparsebody::pose::JointMap& map,
             const sparsebody::pose::Skeleton* truth, std::size_t frames) {
    skel_ = &avatar, map_ = map, truth_skel_ = truth;
    const std::size_t ja = static_cast<std::size_t>(avatar.size()), jt = truth ? static_cast<std::size_t>(truth->size()) : 0;
    local_.reserve(frames * ja * 4);
    root_.reserve(frames * 3);
    truth_mm_.reserve(frames * jt * 3);
    truth_frame_.reserve(frames);
    tracker_mm_.reserve(frames * sparsebody::trackers::kTrackerCount * 3);
    tracker_q_.reserve(frames * sparsebody::trackers::kTrackerCount * 4);
    flags_.reserve(frames);
  }

  // One output frame: the pose (local rotations, root at the standard size; `user` scales the root
  // to the user, metres), the feet's contacts, the trackers shown with it and, with ground truth,
  // its world pose and clip frame. The avatar's positions are made at write(), as the output BVH's
  // are: every frame on the skeleton the run ended with (its proportions and the last `user` size).
  void add(const sparsebody::pose::BodyPose& p, double user, const bool (&contact)[2], const sparsebody::trackers::TrackerFrame& trk,
           const sparsebody::pose::WorldPose* truth, int truth_frame) {
    for (int j = 0; j < skel_->size(); ++j) {
      const Eigen::Quaterniond& q = p.local[static_cast<std::size_t>(j)];
      local_.insert(local_.end(), {q.x(), q.y(), q.z(), q.w()});
    }
    for (int k = 0; k < 3; ++k) root_.push_back(p.root_position[k] * user);
    last_user_ = user;
    if (truth_skel_ && truth) {
      for (int j = 0; j < truth_skel_->size(); ++j)
        for (int k = 0; k < 3; ++k) truth_mm_.push_back(mm(truth->position[j][k]));
      truth_frame_.push_back(truth_frame);
    }
    std::uint8_t f = static_cast<std::uint8_t>((contact[0] ? 1 : 0) | (contact[1] ? 2 : 0));
    for (int t = 0; t < sparsebody::trackers::kTrackerCount; ++t) {
      const auto& p = trk.pose[t];
      const bool ok = trk.valid[t] && std::isfinite(p.position.x) && std::isfinite(p.position.y) && std::isfinite(p.position.z);
      if (ok) f = static_cast<std::uint8_t>(f | (4 << t));
      tracker_mm_.push_back(ok ? mm(p.position.x) : 0);
      tracker_mm_.push_back(ok ? mm(p.position.y) : 0);
      tracker_mm_.push_back(ok ? mm(p.position.z) : 0);
      const float q[4] = {p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w};
      for (float c : q) tracker_q_.push_back(static_cast<std::int16_t>(ok && std::isfinite(c) ? std::lround(std::fmax(-1.f, std::fmin(1.f, c)) * 32767) : 0));
    }
    flags_.push_back(f);
  }

  std::size_t frames() const noexcept { return flags_.size(); }

  // Writes the page: template_path with three_js_path's code and the recording inlined. info: a JSON
  // object (title, model, input, fps, metrics ...) the page shows. Throws std::runtime_error naming
  // the file that cannot be read or written.
  void write(const std::string& path, const std::string& template_path, const std::string& three_js_path, const std::string& info_json) const;

 private:
  // Millimetres; non-finite becomes 0 (a bad pose frame is not a reason to lose the page).
  static std::int32_t mm(double metres) noexcept {
    return std::isfinite(metres) ? static_cast<std::int32_t>(std::lround(std::fmax(-2e6, std::fmin(2e6, metres * 1000.0)))) : 0;
  }

  const sparsebody::pose::Skeleton* skel_ = nullptr;
  sparsebody::pose::JointMap map_{};
  const sparsebody::pose::Skeleton* truth_skel_ = nullptr;
  std::vector<double> local_, root_;  // per frame: J quaternions (x y z w), the root (m, user size)
  double last_user_ = 1.0;
  std::vector<std::int32_t> truth_mm_, truth_frame_, tracker_mm_;
  std::vector<std::int16_t> tracker_q_;
  std::vector<std::uint8_t> flags_;  // bit 0/1: left/right foot contact; bit 2+t: tracker t valid
};

// The three.js file the page inlines: --three-js PATH, else npm's copy (examples/viewer/node_modules,
// path set by CMake), else Debian's libjs-three. Empty after printing one error line when none is
// usable (missing, or an ES-module build without the global THREE).
std::string find_three_js(const std::string& override_path);

}  // namespace demo
