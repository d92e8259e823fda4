// A validation-style session: a CMU clip (assimp-testmodels' 01_01.bvh) through device-realistic
// synthesis (recordings/tracker_synthesis.hpp: 72 Hz, eye and grip offsets, OpenXR orientations,
// no T-pose) and the LoBSTr / Neural3Points pipelines with their shipped weights, calibrating
// automatically like a real headset session. 01_01 is a jumping clip without one second of standing
// still anywhere, so the session holds its frame at 8.3 s (upright, arms down) for 2.5 s: the user
// moves from the first frame, stands still at 8.3 s, then goes on.
#include <doctest/doctest.h>

#include <fstream>
#include <string>
#include <type_traits>

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

const Session& session() {
  static const Session s = [] {
    Session s;
    s.clip = recordings::with_held_frame(recordings::read_bvh(SPARSEBODY_TEST_CLIP), 8.3, 2.5);
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
void set_base(P& p, const features::Calibration& c) {
  if constexpr (std::is_same_v<std::decay_t<decltype(p.calibration())>, features::Calibration>) {
    p.set_calibration(c);
  } else {
    features::n3p::N3PCalibration n;
    n.base = c;
    p.set_calibration(n);
  }
}

// Mean distance of the output head joint (user's size) from where the eye offset puts it
// (headset - R_cal e), over the frames after calibration: all of them, and standing still.
struct HeadError {
  double all = 0, standing = 0;
  long n = 0, n_standing = 0;
};

template <class P>
HeadError run(P& p, const std::vector<trackers::TrackerFrame>& frames, const features::DeviceModel& d) {
  const int head = p.joint_map()[pose::Role::Head];
  HeadError e;
  for (const auto& f : frames) {
    if (p.push(f) == 0 || !p.has_output()) continue;
    if (p.calibration_report().status != features::CalibrationStatus::Calibrated) continue;
    const Eigen::Quaterniond qc = trackers::to_eigen(f.pose[0].orientation) * base_of(p.calibration()).offset[0];
    const Eigen::Vector3d joint = trackers::to_eigen(f.pose[0].position) - qc * d.eye;
    const double err = (p.world().position[head] * p.user_scale() - joint).norm();
    e.all += err, ++e.n;
    if (f.time > 8.8 && f.time < 10.8) e.standing += err, ++e.n_standing;  // inside the 2.5 s stand, 0.5 s after it began
  }
  e.all /= std::max(1L, e.n);
  e.standing /= std::max(1L, e.n_standing);
  return e;
}

// max_standing: the pipeline's head error bound while standing (LoBSTr's head hangs from the spine
// under the pelvis tracker: 5.4 cm off the head joint even with trackers at the joints).
template <class P, class W, class C>
void check_pipeline(const W& weights, C cfg, const char* name, double max_standing) {
  INFO(name);
  const Session& s = session();
  P p(weights, cfg);
  CHECK(p.calibration_report().status == features::CalibrationStatus::Default);
  const HeadError e = run(p, s.devices.frames, features::DeviceModel{});
  const auto& r = p.calibration_report();
  MESSAGE((std::string(name) + ": " + r.message));
  REQUIRE(r.status == features::CalibrationStatus::Calibrated);
  CHECK(r.first_time >= 7.5);  // the stand (the clip's own moments before it are not still)
  CHECK(r.last_time <= 10.8 + 1e-9);
  Eigen::Vector3d h, top;
  Eigen::Quaterniond R;
  clip_head(s, 9.0, h, top, R);
  // The clip's true stature: the top of its head (the Head end site) standing. (CMU's end site is
  // only 10 cm above its head joint, below the vertex: the estimate comes out 5.3 % above it; 4.5 %
  // before the eye height was taken upright, level_head: the performer's head is bent a little.)
  MESSAGE("stature " << r.stature << " m, clip head top " << top.y() << " m, head joint " << h.y() << " m");
  CHECK(std::abs(r.stature / top.y() - 1) < 0.06);
  // the window's eye height is the clip's standing head joint + e.y (the median of a still window;
  // the upright eye height: within 2 mm, before level_head within 2 cm)
  CHECK(std::abs(r.eye_height - (h.y() + 0.08)) < 0.002);
  // the same motion with trackers at the joints and the clip's size given: the pipeline's own head error
  P q(weights, cfg);
  features::Calibration at_joints;
  at_joints.scale = 1.0 / (h.y() / p.meta().standing_head_height);
  set_base(q, at_joints);
  recordings::DeviceSynthesis joint_opt;
  joint_opt.devices = features::DeviceModel::none();
  joint_opt.rate = 72;
  auto joints = recordings::synthesize_device_trackers(s.clip, s.map, s.units, joint_opt);
  for (auto& f : joints.frames)  // back to the body convention the identity calibration expects
    for (auto& x : f.pose) x.orientation = trackers::to_xr(Eigen::Quaterniond(trackers::to_eigen(x.orientation) * features::DeviceModel::default_orientation_offset()));
  const HeadError b = run(q, joints.frames, features::DeviceModel::none());
  MESSAGE("head joint error, devices + automatic calibration: " << e.all << " m (" << e.n << " frames), standing " << e.standing
          << " m; trackers at the joints: " << b.all << " m, standing " << b.standing << " m");
  REQUIRE(e.n > 100);
  CHECK(e.standing < max_standing);
  CHECK(e.standing < b.standing + 0.025);  // the device offsets and automatic calibration add at most 2.5 cm
  CHECK(e.all < b.all + 0.03);
}

TEST_CASE("device-realistic CMU session: LoBSTr calibrates automatically (stature, head on the eye offset)") {
  check_pipeline<avatar::LoBSTrCompact>(avatar::LoBSTrCompact::load(kDir + "/lobstr_compact.weights.json"), avatar::LoBSTrConfig{}, "lobstr", 0.08);
}

TEST_CASE("device-realistic CMU session: Neural3Points calibrates automatically (stature, head on the eye offset)") {
  avatar::N3PConfig cfg;
  check_pipeline<avatar::N3PDirect>(avatar::N3PDirect::load(kDir + "/n3p"), cfg, "n3p", 0.03);
}

TEST_CASE("device-realistic CMU session with a perturbed device fit and timing jitter still calibrates") {
  const Session& s = session();
  Eigen::Vector3d h, top;
  Eigen::Quaterniond R;
  clip_head(s, 9.0, h, top, R);
  for (unsigned seed : {1u, 2u, 3u}) {
    INFO("seed " << seed);
    recordings::DeviceSynthesis opt;
    opt.perturb = true;
    opt.seed = seed;
    opt.timing_jitter = 0.002;
    const auto frames = recordings::synthesize_device_trackers(s.clip, s.map, s.units, opt).frames;
    avatar::N3PDirect p(avatar::N3PDirect::load(kDir + "/n3p"));
    for (const auto& f : frames) p.push(f);
    const auto& r = p.calibration_report();
    MESSAGE("seed " << seed << ": " << r.message);
    REQUIRE(r.status == features::CalibrationStatus::Calibrated);
    // the eye offset varies by +-2 cm per axis: within 3 cm of the nominal eye height, and the
    // stature within 5 % of the one the nominal device model gives for this clip
    CHECK(std::abs(r.eye_height - (h.y() + 0.08)) < 0.03);
    CHECK(std::abs(r.stature / ((h.y() + 0.08) / 0.936) - 1) < 0.05);
    MESSAGE("stature / clip head top = " << r.stature / top.y());
  }
}
