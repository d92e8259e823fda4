// A validation-style session: a CMU clip (assimp-testmodels' 01_01.bvh) through device-realistic
// synthesis (recordings/tracker_synthesis.hpp: 72 Hz, eye and grip offsets, OpenXR orientations,
// no T-pose) and the LoBSTr / Neural3Points pipelines with their shipped weights, calibrating
// automatically like a real headset session. 01_01 is a jumping clip without one second of standing
// still anywhere, so the session holds its frame at 8.3 s (upright, arms down) for 2.5 s: the user
// moves from the first frame, stands still at 8.3 s, then goes on.
#include <doctest/doctest.h>

#include <fstream>
#include <string>

#include "sparsebody/avatar/lobstr_pipeline.hpp"
#include "sparsebody/avatar/n3p_direct.hpp"
#include "sparsebody/recordings/bvh.hpp"
#include "sparsebody/recordings/tracker_synthesis.hpp"

using namespace sparsebody;

namespace {
const std::string kDir = SPARSEBODY_WEIGHTS_DIR;

struct Session {
  recordings::BvhClip clip;
  pose::JointMap map;
  double units = 1;
  recordings::SyntheticTrackers joints, devices;
};

// The clip with frame `at` (seconds) held for `hold` seconds.
recordings::BvhClip with_stand(recordings::BvhClip c, double at, double hold) {
  const int f = static_cast<int>(std::lround(at / c.frame_time)), n = static_cast<int>(std::lround(hold / c.frame_time));
  const std::size_t at_row = static_cast<std::size_t>(f) * c.channel_count, cc = static_cast<std::size_t>(c.channel_count);
  std::vector<double> m(c.motion.begin(), c.motion.begin() + static_cast<std::ptrdiff_t>(at_row));
  for (int i = 0; i <= n; ++i) m.insert(m.end(), c.motion.begin() + static_cast<std::ptrdiff_t>(at_row), c.motion.begin() + static_cast<std::ptrdiff_t>(at_row + cc));
  m.insert(m.end(), c.motion.begin() + static_cast<std::ptrdiff_t>(at_row + cc), c.motion.end());
  c.motion = std::move(m);
  c.frames += n;
  return c;
}

const Session& session() {
  static const Session s = [] {
    Session s;
    s.clip = with_stand(recordings::read_bvh(SPARSEBODY_TEST_CLIP), 8.3, 2.5);
    s.map = pose::JointMap::from_names(s.clip.skeleton, "01_01");
    s.units = recordings::guess_units(s.clip.skeleton, s.map);
    s.joints = recordings::synthesize_trackers(s.clip, s.map, s.units);
    recordings::DeviceSynthesis opt;
    opt.rate = 72;
    s.devices = recordings::synthesize_device_trackers(s.clip, s.map, s.units, opt);
    return s;
  }();
  return s;
}

// The clip's head joint and top of the head (Head's end site) at time t, floor at 0.
void clip_head(const Session& s, double t, Eigen::Vector3d& head, Eigen::Vector3d& top, Eigen::Quaterniond& R) {
  const int f = std::min(s.clip.frames - 1, static_cast<int>(std::lround(t / s.clip.frame_time)));
  pose::BodyPose tmp;
  tmp.resize(s.clip.skeleton.size());
  pose::Vec3Vector tr(static_cast<std::size_t>(s.clip.skeleton.size()));
  pose::WorldPose w;
  w.resize(s.clip.skeleton.size());
  s.clip.world_pose(f, tmp, tr, w, s.units);
  const int h = s.map[pose::Role::Head];
  head = w.position[h] - Eigen::Vector3d(0, s.joints.floor, 0);
  R = w.rotation[h];
  top = head + R * (s.clip.end_offset[h] * s.units);
}
}  // namespace

TEST_CASE("device synthesis: headset at head + R e, grips at wrist + R g, OpenXR orientations, 72 Hz") {
  const Session& s = session();
  REQUIRE(s.devices.frames.size() > 100);
  CHECK(s.devices.frames[1].time == doctest::Approx(1.0 / 72));
  const double dur = (s.clip.frames - 1) * s.clip.frame_time;
  CHECK(s.devices.frames.back().time <= dur + 1e-9);
  CHECK(s.devices.frames.back().time > dur - 1.0 / 72 - 1e-9);
  // at a clip frame time (t = 0) the device = joint + R d, orientation = R half
  const features::DeviceModel d;
  const auto &j = s.joints.frames[0], &v = s.devices.frames[0];
  for (int k = 0; k < 4; ++k) {
    const Eigen::Quaterniond R = trackers::to_eigen(j.pose[k].orientation);
    const Eigen::Vector3d expect = trackers::to_eigen(j.pose[k].position) + R * d.offset(k);
    CHECK((trackers::to_eigen(v.pose[k].position) - expect).norm() < 1e-5);
    const Eigen::Quaterniond q = trackers::to_eigen(v.pose[k].orientation);
    CHECK(q.angularDistance(R * features::DeviceModel::default_orientation_offset()) < 1e-5);
  }
  // perturbation, jitter and losses: seeded, bounded
  recordings::DeviceSynthesis opt;
  opt.perturb = true;
  opt.seed = 7;
  opt.timing_jitter = 0.002;
  opt.losses_per_second = 0.5;
  const auto a = recordings::synthesize_device_trackers(s.clip, s.map, s.units, opt);
  const auto b = recordings::synthesize_device_trackers(s.clip, s.map, s.units, opt);
  REQUIRE(a.frames.size() == b.frames.size());
  int lost = 0;
  double max_jitter = 0;
  for (std::size_t i = 0; i < a.frames.size(); ++i) {
    CHECK(a.frames[i].time == b.frames[i].time);
    lost += !a.frames[i].valid[0];
    if (i > 0) max_jitter = std::max(max_jitter, std::abs(a.frames[i].time - i / 72.0));
  }
  CHECK(lost > 0);
  CHECK(max_jitter <= 0.002 + 1e-12);
  CHECK(max_jitter > 0.0);
}

const features::Calibration& base_of(const features::Calibration& c) { return c; }
const features::Calibration& base_of(const features::n3p::N3PCalibration& c) { return c.base; }

template <class P>
void check_pipeline(P& p, const char* name) {
  INFO(name);
  const Session& s = session();
  CHECK(p.calibration_report().status == features::CalibrationStatus::Default);
  const int head = p.joint_map()[pose::Role::Head];
  double err_sum = 0;
  long n = 0;
  for (const auto& f : s.devices.frames) {
    if (p.push(f) == 0 || !p.has_output()) continue;
    if (p.calibration_report().status != features::CalibrationStatus::Calibrated) continue;
    // where the eye offset puts the head joint: headset - R_cal e (R_cal = the calibrated headset)
    const Eigen::Quaterniond qc = trackers::to_eigen(f.pose[0].orientation) * base_of(p.calibration()).offset[0];
    const Eigen::Vector3d joint = trackers::to_eigen(f.pose[0].position) - qc * features::DeviceModel{}.eye;
    err_sum += (p.world().position[head] * p.user_scale() - joint).norm();
    ++n;
  }
  const auto& r = p.calibration_report();
  MESSAGE(name << ": " << r.message);
  REQUIRE(r.status == features::CalibrationStatus::Calibrated);
  Eigen::Vector3d h, top;
  Eigen::Quaterniond R;
  clip_head(s, 0.5 * (r.first_time + r.last_time), h, top, R);
  // true stature: the top of the head (the clip's Head end site) standing at the window
  MESSAGE("stature " << r.stature << " m, clip head top " << top.y() << " m, head joint " << h.y() << " m");
  CHECK(r.stature == doctest::Approx(top.y()).epsilon(0.05));
  CHECK(r.eye_height == doctest::Approx(h.y() + 0.08).epsilon(0.02));
  REQUIRE(n > 100);
  MESSAGE("mean head-joint error " << err_sum / n << " m over " << n << " frames");
  CHECK(err_sum / n < 0.05);
}

TEST_CASE("device-realistic CMU session: LoBSTr calibrates automatically (stature, head on the eye offset)") {
  avatar::LoBSTrCompact p(avatar::LoBSTrCompact::load(kDir + "/lobstr_compact.weights.json"));
  check_pipeline(p, "lobstr");
}

TEST_CASE("device-realistic CMU session: Neural3Points calibrates automatically (stature, head on the eye offset)") {
  avatar::N3PDirect p(avatar::N3PDirect::load(kDir + "/n3p"));
  check_pipeline(p, "n3p");
}
