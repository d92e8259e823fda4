// N3PPipeline (direct mode): equals the predictor on clean input, tracker modes per frame (3-point,
// one controller, HMD only), direct-mode IK (hands on controllers, feet pinned), calibration (§7),
// and bad input (NaN, lost trackers, gaps, jumps): defined behaviour, never a NaN out.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "n3p/common.hpp"

using namespace sparsebody;

namespace {
const nlohmann::json& golden() {
  static const nlohmann::json g = n3p_test::read_json(n3p_test::golden_dir() + "/n3p_small.golden.json");
  return g;
}
const n3p_test::SmallPipeline::Weights& weights() {
  static const auto w = n3p_test::SmallPipeline::load(n3p_test::small_prefix());
  return w;
}
bool finite(const n3p_test::SmallPipeline& p) {
  bool ok = p.pose().root_position.allFinite();
  for (int j = 0; j < p.skeleton().size(); ++j) ok &= p.world().position[j].allFinite() && p.pose().local[j].coeffs().allFinite();
  return ok;
}
avatar::N3PConfig no_ik() {
  avatar::N3PConfig c;
  c.foot_ik = c.hand_ik = false;
  c.anchor_head = c.head_reach = c.head_height = false;  // the predictor's own output: no post-processing at all
  return c;
}
}  // namespace

TEST_CASE("n3p pipeline: the head anchor keeps the predicted head on the headset horizontally, in bounded steps") {
  const auto& g = golden();
  auto head_error = [&](bool anchor, double* max_root_step) {
    avatar::N3PConfig c;
    c.anchor_head = anchor;
    n3p_test::SmallPipeline p(weights(), c);
    p.set_calibration({});
    const int head = p.skeleton().find("Head");
    double sum = 0, prev_x = 0, prev_z = 0;
    int n = 0;
    *max_root_step = 0;
    for (int t = 0; t < g["frames"].get<int>(); ++t) {
      const auto f = n3p_test::golden_frame(g, t);
      REQUIRE(p.push(f) == 1);
      const Eigen::Vector3d d = p.world().position[head] - trackers::to_eigen(f.pose[0].position);
      sum += std::hypot(d.x(), d.z());
      ++n;
      const Eigen::Vector3d r = p.pose().root_position;
      if (t > 0) *max_root_step = std::max(*max_root_step, std::hypot(r.x() - prev_x, r.z() - prev_z));
      prev_x = r.x(), prev_z = r.z();
    }
    return sum / n;
  };
  double step_on = 0, step_off = 0;
  const double on = head_error(true, &step_on), off = head_error(false, &step_off);
  MESSAGE("mean horizontal head error: anchored " << on << " m, free " << off << " m");
  CHECK(on < 0.75 * off);  // (a small random-weight network here: it strays metres; the default weights stray cm)
  CHECK(step_on < step_off + 0.03 + 1e-9);  // the anchor moves the body by at most anchor_max_step per step
}

TEST_CASE("n3p pipeline: head height: the body follows a headset above or below where it can put its head") {
  const auto& g = golden();
  const int frames = std::min(120, g["frames"].get<int>());
  // The user steps onto a 0.5 m platform (every tracker rises, 5 cm a frame from frame 20), or
  // kneels (every tracker 0.5 m lower). Head error: |headset y - head joint y| over frames 50..
  auto run = [&](bool follow, double rise, double* head_err, double* lowest_ankle, double* lowest_before) {
    avatar::N3PConfig c;
    c.head_height = follow;
    n3p_test::SmallPipeline p(weights(), c);
    p.set_calibration({});
    const int head = p.skeleton().find("Head");
    const int ankle[2] = {p.skeleton().find("Foot_L"), p.skeleton().find("Foot_R")};
    double sum = 0;
    int n = 0;
    *lowest_ankle = *lowest_before = std::numeric_limits<double>::infinity();
    for (int t = 0; t < frames; ++t) {
      auto f = n3p_test::golden_frame(g, t);
      const double dy = rise * std::clamp((t - 20) / 10.0, 0.0, 1.0);
      for (int k = 0; k < 3; ++k) f.pose[k].position.y += static_cast<float>(dy);
      REQUIRE(p.push(f) == 1);
      REQUIRE(finite(p));
      const double low = std::min(p.world().position[ankle[0]].y(), p.world().position[ankle[1]].y());
      if (t < 20) *lowest_before = std::min(*lowest_before, low);
      else *lowest_ankle = std::min(*lowest_ankle, low);
      if (t >= 50) {
        sum += std::abs(f.pose[0].position.y - p.world().position[head].y());
        ++n;
      }
    }
    *head_err = sum / n;
  };
  double up_on, up_off, down_on, down_off, low, before, low_off, before_off;
  run(true, 0.5, &up_on, &low, &before);
  run(false, 0.5, &up_off, &low_off, &before_off);
  MESSAGE("0.5 m up: mean vertical head error " << up_on << " m following, " << up_off << " m not");
  CHECK(up_off > 0.3);
  CHECK(up_on < 0.02 + 0.01);  // the dead band, and pins released once the headset is out of their reach
  run(true, -0.5, &down_on, &low, &before);
  run(false, -0.5, &down_off, &low_off, &before_off);
  MESSAGE("0.5 m down: mean vertical head error " << down_on << " m following, " << down_off << " m not; lowest ankle "
                                                 << low << " m (before: " << before << " m), not following " << low_off << " m");
  CHECK(down_off > 0.3);
  CHECK(down_on < 0.02 + 0.01);
  CHECK(low > before - 0.02);  // the legs bend: the feet are not pushed into the floor
}

TEST_CASE("n3p pipeline: without IK it reproduces the PyTorch reference, controller flags -> modes") {
  const auto& g = golden();
  n3p_test::SmallPipeline p(weights(), no_ik());
  // synthetic trackers at the joints in the body convention: the identity calibration
  p.set_calibration({});
  int modes[3] = {0, 0, 0};
  double worst = 0;
  for (int t = 0; t < g["frames"].get<int>(); ++t) {
    const auto f = n3p_test::golden_frame(g, t);
    REQUIRE(p.push(f) == 1);
    REQUIRE(p.has_output());
    const int m = p.predicted_controllers();
    CHECK(m == (!f.valid[1]) + (!f.valid[2]));
    ++modes[m];
    for (int j = 0; j < p.skeleton().size(); ++j)
      for (int i = 0; i < 3; ++i)
        worst = std::max(worst, std::abs(p.world().position[j][i] - g["positions"][t][3 * j + i].get<double>()));
  }
  CHECK(worst < 1e-4);
  CHECK(modes[0] > 0);
  CHECK(modes[1] >= 30);
  CHECK(modes[2] >= 30);
}

TEST_CASE("n3p pipeline: HMD-only by configuration ignores tracked controllers") {
  const auto& g = golden();
  avatar::N3PConfig c = no_ik();
  c.use_controllers = false;
  n3p_test::SmallPipeline hmd(weights(), c), three(weights(), no_ik());
  // synthetic trackers at the joints in the body convention: the identity calibration
  hmd.set_calibration({});
  three.set_calibration({});
  double diff = 0;
  for (int t = 0; t < 50; ++t) {
    auto f = n3p_test::golden_frame(g, t);
    hmd.push(f);
    three.push(f);
    CHECK(hmd.predicted_controllers() == 2);
    CHECK(three.predicted_controllers() == 0);
    diff = std::max(diff, (hmd.world().position[8] - three.world().position[8]).norm());
  }
  CHECK(diff > 1e-4);  // the hands really come from o*
  CHECK(finite(hmd));
}

TEST_CASE("n3p direct mode: hands on the controllers, feet pinned while in contact") {
  const auto& g = golden();
  for (const auto pin : {avatar::N3PConfig::Pin::Toe, avatar::N3PConfig::Pin::Ankle}) {
    CAPTURE(pin == avatar::N3PConfig::Pin::Toe);
    avatar::N3PConfig c;
    c.pin = pin;
    c.contact_threshold = -1.0;  // every frame in contact: both feet lock
    c.foot_max_drift = 100.0;   // random weights: feet jump about; keep the locks for the test
    n3p_test::SmallPipeline p(weights(), c), free(weights(), no_ik());
    // synthetic trackers at the joints in the body convention: the identity calibration
    p.set_calibration({});
    free.set_calibration({});
    const int hand[2] = {p.skeleton().find("Hand_L"), p.skeleton().find("Hand_R")};
    // the pinned point: the toe base (its ankle turns about it), or the ankle
    const bool toe = pin == avatar::N3PConfig::Pin::Toe;
    const int foot[2] = {p.skeleton().find(toe ? "Toes_L" : "Foot_L"), p.skeleton().find(toe ? "Toes_R" : "Foot_R")};
    const int upleg[2] = {p.skeleton().find("UpperLeg_L"), p.skeleton().find("UpperLeg_R")};
    int on_controller = 0, checked = 0, pinned = 0;
    Eigen::Vector3d prev[2];
    for (int t = 0; t < 60; ++t) {
      const auto f = n3p_test::golden_frame(g, t);
      p.push(f);
      free.push(f);
      REQUIRE(finite(p));
      for (int s = 0; s < 2; ++s) {
        const Eigen::Vector3d target = trackers::to_eigen(f.pose[1 + s].position);
        // IK never moves a hand away from its controller
        if (f.valid[1 + s])
          CHECK((p.world().position[hand[s]] - target).norm() <= (free.world().position[hand[s]] - target).norm() + 1e-9);
        const double reach = p.skeleton().offsets[hand[s]].norm() + p.skeleton().offsets[hand[s] - 1].norm();
        const int shoulder = hand[s] - 2;
        if (f.valid[1 + s] && (target - p.world().position[shoulder]).norm() < reach - 1e-3) {
          ++checked;
          on_controller += (p.world().position[hand[s]] - target).norm() < 1e-6;
        }
        if (t > 0 && p.foot_locked(s) && (prev[s] - p.world().position[upleg[s]]).norm() < 0.8) {
          pinned += (p.world().position[foot[s]] - prev[s]).norm() < 1e-6;
        }
        prev[s] = p.world().position[foot[s]];
      }
    }
    CHECK(on_controller == checked);  // (random weights: the controllers are seldom within reach)
    CHECK(pinned > 5);  // (random weights: the hips wander, locks out of reach are released)
  }
}

TEST_CASE("n3p calibration (§7): T-pose offsets put the devices' joints at the wrists and head") {
  const auto& s = n3p_test::SmallPredictor(weights()).skeleton();
  const auto w = features::n3p::tpose_wrists(s);
  CHECK(w[0].x() > 0.4);   // left wrist to the left (+X of the facing frame)
  CHECK(w[1].x() < -0.4);
  CHECK(std::abs(w[0].y() - w[1].y()) < 1e-3);
  // a user 10 % taller than the standard skeleton, facing -Z (OpenXR), controllers 8 cm off the wrists
  const double user = 1.1, head_h = 1.378 * user;
  trackers::TrackerFrame f;
  const Eigen::Matrix3d yaw = features::yaw_frame(Eigen::Vector3d(0, 0, -1), Eigen::Matrix3d::Identity());
  const Eigen::Vector3d head(0.3, head_h, 2.0);  // the head joint; the headset is the eye offset from it
  const Eigen::Quaterniond qh = Eigen::Quaterniond::Identity();  // OpenXR: the headset looks along its -Z
  const features::DeviceModel devices;
  f.pose[0] = {trackers::to_xr(qh), trackers::to_xr(Eigen::Vector3d(head + yaw * devices.eye))};
  Eigen::Vector3d wrist_world[2];
  for (int k = 1; k < 3; ++k) {
    wrist_world[k - 1] = head + yaw * (w[k - 1] * user);
    const Eigen::Quaterniond q(Eigen::AngleAxisd(0.4 * k, Eigen::Vector3d(1, 1, 0).normalized()));
    const Eigen::Vector3d device = wrist_world[k - 1] + q * Eigen::Vector3d(0, -0.02, 0.08);
    f.pose[k] = {trackers::to_xr(q), trackers::to_xr(device)};
  }
  f.valid = {true, true, true, false};
  features::n3p::N3PCalibration c;
  REQUIRE(c.from_tpose(f, s, 0.908, 1.378));
  CHECK(c.base.scale == doctest::Approx(1 / user).epsilon(1e-6));
  for (int k = 1; k < 3; ++k) {
    trackers::PoseD d{trackers::to_eigen(f.pose[k].position), trackers::to_eigen(f.pose[k].orientation)};
    d.orientation.normalize();
    // d_k in the calibrated frame (the facing frame here): device - wrist = R_cal d_k
    CHECK((yaw * c.base.position_offset[k] - d.orientation * Eigen::Vector3d(0, -0.02, 0.08)).norm() < 1e-5);
    const auto j = c.apply(k, d);
    CHECK((j.p - wrist_world[k - 1] / user).norm() < 1e-5);
    // calibrated orientation = the facing frame at calibration
    CHECK((j.fwd - yaw.col(2)).norm() < 1e-5);
  }
  CHECK(c.hand_offsets);
  // not a T-pose (a controller at the head): orientations and scale only, no wrist offsets
  f.pose[1].position = f.pose[0].position;
  REQUIRE(c.from_tpose(f, s, 0.908, 1.378));
  CHECK_FALSE(c.hand_offsets);  // the device model's grip offsets (were zero before the device model)
  CHECK((c.base.position_offset[1] - devices.grip_left).norm() == 0.0);
  CHECK((c.base.position_offset[2] - devices.grip_right).norm() == 0.0);
  CHECK((c.base.position_offset[0] - devices.eye).norm() == 0.0);
  // no usable headset: unchanged, false
  f.valid[0] = false;
  CHECK_FALSE(c.from_tpose(f, s, 0.908, 1.378));
  CHECK(c.base.scale == doctest::Approx(1 / user).epsilon(1e-6));
}

TEST_CASE("n3p pipeline: bad input never produces a NaN and is handled as defined") {
  const auto& g = golden();
  n3p_test::SmallPipeline p(weights());
  // synthetic trackers at the joints in the body convention: the identity calibration
  p.set_calibration({});
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // no headset yet: no output
  auto f0 = n3p_test::golden_frame(g, 0);
  f0.valid[0] = false;
  p.push(f0);
  CHECK_FALSE(p.has_output());
  int t = 1;
  auto feed = [&](auto&& edit) {
    auto f = n3p_test::golden_frame(g, t % 200);
    f.time = t / 30.0;
    f.valid = {true, true, true, false};
    edit(f);
    p.push(f);
    ++t;
    REQUIRE(finite(p));
  };
  for (int i = 0; i < 20; ++i) feed([](trackers::TrackerFrame&) {});
  CHECK(p.has_output());
  // NaN positions and orientations on every tracker, with valid flags set
  for (int i = 0; i < 5; ++i)
    feed([&](trackers::TrackerFrame& f) {
      f.pose[0].position.x = static_cast<float>(nan);
      f.pose[1].orientation.w = static_cast<float>(nan);
      f.pose[2].position.y = std::numeric_limits<float>::infinity();
    });
  CHECK(p.predicted_controllers() == 2);  // the controllers were rejected: o* stands in
  // non-unit quaternion, zero quaternion
  feed([](trackers::TrackerFrame& f) { f.pose[1].orientation = {0, 0, 0, 0}; f.pose[2].orientation = {3, 0, 0, 0}; });
  CHECK(p.predicted_controllers() == 2);
  // one controller lost for a while
  for (int i = 0; i < 30; ++i) feed([](trackers::TrackerFrame& f) { f.valid[2] = false; });
  CHECK(p.predicted_controllers() == 1);
  // a controller 5 m away from the headset (glitch): missing for that frame
  feed([](trackers::TrackerFrame& f) { f.pose[1].position.x += 5; });
  CHECK(p.predicted_controllers() == 1);
  feed([](trackers::TrackerFrame&) {});
  CHECK(p.predicted_controllers() == 0);  // used again at once
  // a headset jump of 3 m for one frame: held
  feed([](trackers::TrackerFrame& f) { f.pose[0].position.x += 3; });
  // headset lost for 2 s: held, then a reset; output stays finite
  for (int i = 0; i < 60; ++i) feed([](trackers::TrackerFrame& f) { f.valid[0] = false; });
  // a time gap of 3 s (resampler restart) and a time going backwards
  t += 90;
  feed([](trackers::TrackerFrame&) {});
  feed([](trackers::TrackerFrame& f) { f.time -= 1.0; });
  // tracking origin moved by 10 m for good: accepted after a few frames
  for (int i = 0; i < 10; ++i)
    feed([](trackers::TrackerFrame& f) {
      for (int k = 0; k < 3; ++k) f.pose[k].position.z += 10;
    });
  CHECK(p.has_output());
  // all trackers invalid for long
  for (int i = 0; i < 40; ++i) feed([](trackers::TrackerFrame& f) { f.valid = {false, false, false, false}; });
  // NaN time: dropped
  auto f = n3p_test::golden_frame(g, 3);
  f.time = nan;
  CHECK(p.push(f) == 0);
  // back to normal
  for (int i = 0; i < 30; ++i) feed([](trackers::TrackerFrame&) {});
  CHECK(p.has_output());
  CHECK(p.predicted_controllers() == 0);
}

TEST_CASE("n3p predictor: absurd tracker values cannot make the state non-finite") {
  n3p_test::SmallPredictor p(weights());
  features::n3p::TrackerSet o;
  for (int k = 0; k < 3; ++k) o[k].p = Eigen::Vector3d(1e30, -1e30, 1e30);
  for (int i = 0; i < 10; ++i) {
    p.step(o, {true, true, true});
    CHECK(p.pose().root_position.allFinite());
    for (const auto& q : p.pose().local) CHECK(q.coeffs().allFinite());
  }
  o[0].p.x() = std::numeric_limits<double>::quiet_NaN();
  CHECK_FALSE(p.step(o, {true, true, true}));
}
