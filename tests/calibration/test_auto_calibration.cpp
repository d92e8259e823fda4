// Automatic calibration from standing windows (features/auto_calibration.hpp) on synthetic headset
// sessions: when a window is found, what it gives, refinement, refusal, and broken windows.
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <string>

#include "sparsebody/avatar/lobstr_pipeline.hpp"
#include "sparsebody/features/auto_calibration.hpp"
#include "support/standing_stream.hpp"

using namespace sparsebody;
using sparsebody_test::Phase;

namespace {
constexpr double kStdHead = 1.38;

// Feeds frames (already at the model rate) to a calibrator as a pipeline does after its sanitizer.
struct Feeder {
  features::AutoCalibration cal;
  int changes = 0;
  explicit Feeder(features::AutoCalibrationConfig cfg = {}) : cal(features::DeviceModel{}, kStdHead, cfg) {}
  void feed(const trackers::TrackerFrame& f) {
    std::array<trackers::PoseD, trackers::kTrackerCount> p;
    std::array<bool, trackers::kTrackerCount> v;
    for (int k = 0; k < trackers::kTrackerCount; ++k) {
      p[k].position = trackers::to_eigen(f.pose[k].position);
      p[k].orientation = trackers::to_eigen(f.pose[k].orientation);
      v[k] = f.valid[k];
    }
    changes += cal.push(f.time, p, v);
  }
  void feed(const std::vector<trackers::TrackerFrame>& fs) {
    for (const auto& f : fs) feed(f);
  }
  const features::CalibrationReport& r() const { return cal.report(); }
};

// Horizontal steps of the two toes between consecutive outputs of a LoBSTr pipeline, in the user's
// metres (world times user scale, so a rescale that moves a foot shows as a step).
struct ToeSteps {
  int toe[2];
  Eigen::Vector3d prev[2];
  bool have = false;
  template <class P>
  explicit ToeSteps(const P& p) : toe{p.joint_map()[pose::Role::ToeL], p.joint_map()[pose::Role::ToeR]} {}
  // This output's step of each toe from the previous one; nullopt on the first output.
  template <class P>
  std::optional<std::array<double, 2>> next(const P& p) {
    std::array<double, 2> step{};
    for (int k = 0; k < 2; ++k) {
      const Eigen::Vector3d now = p.world().position[toe[k]] * p.user_scale();
      step[k] = std::hypot(now.x() - prev[k].x(), now.z() - prev[k].z());
      prev[k] = now;
    }
    const bool had = have;
    have = true;
    if (!had) return std::nullopt;
    return step;
  }
};

bool finite(const features::Calibration& c) {
  bool ok = std::isfinite(c.scale) && std::isfinite(c.floor);
  for (int k = 0; k < 4; ++k) ok &= c.offset[k].coeffs().allFinite() && c.position_offset[k].allFinite();
  return ok;
}
}  // namespace

TEST_CASE("auto calibration: standing still 2 s then walking is calibrated from the stand") {
  Feeder f;
  f.feed(sparsebody_test::session({{Phase::Stand, 2.0, 1.65}, {Phase::Walk, 3.0, 1.65}}));
  const auto& r = f.r();
  CHECK(r.status == features::CalibrationStatus::Calibrated);
  CHECK(r.source == features::CalibrationSource::Automatic);
  CHECK(f.changes == 3);  // the body sized to the first frame's headset, the provisional estimate after 0.5 s, the whole window's
  CHECK_FALSE(r.provisional);
  CHECK(r.first_time >= 0.0);
  CHECK(r.last_time <= 2.0);
  CHECK(r.last_time - r.first_time >= 1.0 - 1e-9);
  CHECK(r.eye_height == doctest::Approx(1.65).epsilon(0.002).scale(0));
  CHECK(r.stature == doctest::Approx(1.65 / 0.936).epsilon(0.002).scale(0));
  CHECK(f.cal.calibration().scale == doctest::Approx(kStdHead / (1.65 - 0.08)).epsilon(0.002).scale(0));
  CHECK(r.confidence > 0.4);
  CHECK(r.confidence <= 0.7 + 1e-9);  // one window
  CHECK(std::string(r.message).find("automatic: standing at") == 0);
  // orientation offsets: every calibrated tracker has the body's facing frame at the window, the
  // pelvis tracker the standard standing pelvis frame (facing x DeviceModel::pelvis_standing)
  const auto fr = sparsebody_test::session({{Phase::Stand, 0.1, 1.65}})[0];
  const Eigen::Matrix3d facing = features::Calibration::facing(trackers::to_eigen(fr.pose[0].orientation));
  for (int k = 0; k < 4; ++k) {
    const Eigen::Matrix3d R = (trackers::to_eigen(fr.pose[k].orientation) * f.cal.calibration().offset[k]).toRotationMatrix();
    const Eigen::Matrix3d want = k == 3 ? Eigen::Matrix3d(facing * features::DeviceModel{}.pelvis_standing.toRotationMatrix()) : facing;
    CHECK((R - want).norm() < 1e-3);
  }
  CHECK(facing.col(2).dot(Eigen::Vector3d(-std::sin(0.3), 0, -std::cos(0.3))) > 0.999);  // Z = where the user looks
}

TEST_CASE("auto calibration: walking from frame 0, standing at 5 s") {
  Feeder f;
  const auto walk = sparsebody_test::session({{Phase::Walk, 5.0, 1.70}, {Phase::Stand, 3.0, 1.70}});
  for (std::size_t i = 0; i < walk.size(); ++i) {
    f.feed(walk[i]);
    if (walk[i].time < 5.4) REQUIRE(f.r().status == features::CalibrationStatus::Default);
  }
  CHECK(f.r().status == features::CalibrationStatus::Calibrated);
  CHECK(f.r().first_time >= 5.0 - 1e-9);
  CHECK(f.r().stature == doctest::Approx(1.70 / 0.936).epsilon(0.002).scale(0));
}

TEST_CASE("auto calibration: refinement - higher replaces, same is averaged, lower (sitting) is skipped") {
  Feeder f;
  f.feed(sparsebody_test::session({{Phase::Stand, 2.0, 1.60},   // slouched at first
                                   {Phase::Walk, 1.0, 1.60},
                                   {Phase::Stand, 2.0, 1.66},   // upright: replaces
                                   {Phase::Walk, 1.0, 1.66},
                                   {Phase::Stand, 2.0, 1.67},   // the same stand height: averaged
                                   {Phase::Walk, 1.0, 1.67},
                                   {Phase::Stand, 3.0, 1.20},   // sitting: skipped
                                   {Phase::Walk, 1.0, 1.66}}));
  const auto& r = f.r();
  CHECK(r.status == features::CalibrationStatus::Calibrated);
  CHECK(r.replaced == 1);
  CHECK(r.windows == 2);
  CHECK(r.skipped == 1);
  CHECK(f.changes == 5);  // sized to the headset, the provisional estimate of the first stand, its window, the replacement, the average
  CHECK(r.eye_height == doctest::Approx(1.665).epsilon(0.002).scale(0));
  CHECK(r.confidence > 0.7);  // two agreeing windows
  CHECK(std::string(r.message).find("1 lower") != std::string::npos);
}

TEST_CASE("auto calibration: a short first stand gives a provisional estimate that a full window replaces") {
  const auto s = sparsebody_test::session({{Phase::Stand, 0.7, 1.60}, {Phase::Walk, 1.0, 1.60},
                                           {Phase::Stand, 2.0, 1.20}, {Phase::Walk, 1.0, 1.20},    // sitting
                                           {Phase::Stand, 2.0, 1.58}, {Phase::Walk, 1.0, 1.58}});  // a full stand
  Feeder f;
  std::size_t i = 0;
  for (; s[i].time < 1.7; ++i) f.feed(s[i]);
  CHECK(f.r().status == features::CalibrationStatus::Calibrated);
  CHECK(f.r().provisional);
  CHECK(f.changes == 2);  // sized to the first frame's headset, then the provisional estimate
  CHECK(f.r().last_time - f.r().first_time == doctest::Approx(0.5).epsilon(0.05).scale(0));  // its first 0.5 s
  CHECK(f.r().eye_height == doctest::Approx(1.60).epsilon(0.002).scale(0));
  CHECK(std::string(f.r().message).find("automatic (provisional): standing at") == 0);
  for (; s[i].time < 4.7; ++i) f.feed(s[i]);  // sitting (lower) does not replace it
  CHECK(f.r().provisional);
  CHECK(f.r().skipped == 1);
  CHECK(f.changes == 2);
  for (; i < s.size(); ++i) f.feed(s[i]);  // a full stand, a little lower (within 4 cm): replaces it
  CHECK_FALSE(f.r().provisional);
  CHECK(f.r().windows == 1);
  CHECK(f.changes == 3);
  CHECK(f.r().eye_height == doctest::Approx(1.58).epsilon(0.002).scale(0));
  CHECK(f.r().first_time >= 4.7);
  CHECK(std::string(f.r().message).find("automatic: standing at") == 0);
}

TEST_CASE("auto calibration: a bent stand is raised when the headset then stays above it (AutoCalibration::rise)") {
  // a crouched, still start (every stillness test passes at 1.50 m), then walking upright at 1.65 m
  const auto s = sparsebody_test::session({{Phase::Stand, 2.0, 1.50}, {Phase::Walk, 3.0, 1.65}});
  Feeder f;
  std::size_t i = 0;
  for (; s[i].time < 2.1; ++i) f.feed(s[i]);  // the stand's window closes as the walk begins
  REQUIRE(f.r().status == features::CalibrationStatus::Calibrated);
  REQUIRE(f.r().raised == 0);
  CHECK(f.r().eye_height == doctest::Approx(1.50).epsilon(0.002).scale(0));
  const features::Calibration stand = f.cal.calibration();
  const int before = f.changes;
  double raised_at = -1;
  for (; i < s.size(); ++i) {
    f.feed(s[i]);
    if (raised_at < 0 && f.r().raised) raised_at = s[i].time;
  }
  CHECK(f.r().raised == 1);
  CHECK(f.changes == before + 1);
  CHECK(raised_at == doctest::Approx(2.0 + f.cal.config().rise_time).epsilon(0.04).scale(0));  // rise_time after the walk begins
  // the lowest headset height of the run: the walk's 1.65 m less its 2 cm bob
  CHECK(f.r().eye_height == doctest::Approx(1.63).epsilon(0.003).scale(0));
  CHECK(f.r().stature == doctest::Approx(f.r().eye_height / 0.936).epsilon(1e-9).scale(0));
  CHECK(f.cal.calibration().scale == doctest::Approx(kStdHead / (f.r().eye_height - 0.08)).epsilon(1e-9).scale(0));
  CHECK(f.r().status == features::CalibrationStatus::Calibrated);
  CHECK(f.r().confidence <= 0.5);
  for (int k = 0; k < 4; ++k) CHECK(f.cal.calibration().offset[k].angularDistance(stand.offset[k]) < 1e-12);  // orientations kept
  const std::string m = f.r().message;
  CHECK(m.find("raised from 1.60 m") != std::string::npos);
  CHECK(m.find("a bent stand") != std::string::npos);
  CHECK(finite(f.cal.calibration()));
}

TEST_CASE("auto calibration: no raise for a jump, a walk at the stand's height, an upright stand, tiptoes, or rise_margin = 0") {
  {  // a 40 cm jump while walking (0.57 s in the air) after an upright stand: its vertical speed
     // ends every run before rise_time
    auto s = sparsebody_test::session({{Phase::Stand, 2.0, 1.62}, {Phase::Walk, 2.0, 1.62}});
    const double v0 = std::sqrt(2 * 9.81 * 0.40);
    for (auto& fr : s) {
      const double t = fr.time - 2.5;
      if (t >= 0 && t < 2 * v0 / 9.81) fr.pose[0].position.y += static_cast<float>(v0 * t - 0.5 * 9.81 * t * t);
    }
    Feeder f;
    f.feed(s);
    CHECK(f.r().raised == 0);
    CHECK(f.r().eye_height == doctest::Approx(1.62).epsilon(0.002).scale(0));
  }
  {  // walking at the stand's height, then standing 6 cm higher: a new window replaces the estimate
     // (with orientations), it is not raised
    Feeder f;
    f.feed(sparsebody_test::session({{Phase::Stand, 2.0, 1.60}, {Phase::Walk, 2.0, 1.61}, {Phase::Stand, 2.0, 1.66}, {Phase::Walk, 1.0, 1.66}}));
    CHECK(f.r().raised == 0);
    CHECK(f.r().replaced == 1);
    CHECK(f.r().eye_height == doctest::Approx(1.66).epsilon(0.002).scale(0));
  }
  {  // standing on tiptoe 6 cm up for 2 s, reaching up (the controllers above the headset: no stand)
    auto s = sparsebody_test::session({{Phase::Stand, 2.0, 1.62}, {Phase::Walk, 1.0, 1.62}, {Phase::Stand, 2.0, 1.68},
                                       {Phase::Walk, 1.0, 1.62}});
    for (auto& fr : s)
      if (fr.time >= 3.0 && fr.time < 5.0)
        for (int k = 1; k < 3; ++k) fr.pose[k].position.y = fr.pose[0].position.y + 0.3f;
    Feeder f;
    f.feed(s);
    CHECK(f.r().raised == 0);
    CHECK(f.r().eye_height == doctest::Approx(1.62).epsilon(0.002).scale(0));
  }
  {  // off
    features::AutoCalibrationConfig cfg;
    cfg.rise_margin = 0;
    Feeder f(cfg);
    f.feed(sparsebody_test::session({{Phase::Stand, 2.0, 1.50}, {Phase::Walk, 3.0, 1.65}}));
    CHECK(f.r().raised == 0);
    CHECK(f.r().eye_height == doctest::Approx(1.50).epsilon(0.002).scale(0));
  }
}

namespace {
// The controllers lie on a table while the user stands (a session that starts before the user
// picks them up): flat (a quarter turn about the user's left axis), 0.45 m ahead at 0.76 m.
void put_controllers_on_a_table(std::vector<trackers::TrackerFrame>& frames) {
  const Eigen::Quaterniond q = trackers::to_eigen(frames.front().pose[0].orientation);
  const Eigen::Vector3d fwd = q * Eigen::Vector3d(0, 0, -1), left = q * Eigen::Vector3d(-1, 0, 0);
  const Eigen::Vector3d head = trackers::to_eigen(frames.front().pose[0].position);
  const Eigen::Quaterniond flat = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, left)) * q;
  for (auto& f : frames)
    for (int c = 0; c < 2; ++c) {
      Eigen::Vector3d p = head + 0.45 * fwd + (c == 0 ? 0.15 : -0.15) * left;
      p.y() = 0.76;
      f.pose[1 + c] = {trackers::to_xr(flat), trackers::to_xr(p)};
    }
}

// Each controller's calibrated orientation at a frame against the body's facing frame (rad).
std::array<double, 2> grip_errors(const features::Calibration& c, const trackers::TrackerFrame& f) {
  const Eigen::Matrix3d facing = features::Calibration::facing(trackers::to_eigen(f.pose[0].orientation));
  std::array<double, 2> e{};
  for (int k = 1; k <= 2; ++k)
    e[k - 1] = Eigen::Quaterniond((trackers::to_eigen(f.pose[k].orientation) * c.offset[k]).toRotationMatrix().transpose() * facing)
                   .angularDistance(Eigen::Quaterniond::Identity());
  return e;
}
}  // namespace

TEST_CASE("auto calibration: controllers lying on a table at the stand keep the device model's offset until a stand holds them") {
  auto table = sparsebody_test::session({{Phase::Stand, 2.0, 1.65}});
  put_controllers_on_a_table(table);
  auto rest = sparsebody_test::session({{Phase::Stand, 2.0, 1.65}, {Phase::Walk, 2.0, 1.65}, {Phase::Stand, 2.0, 1.65}});
  for (auto& f : rest) f.time += 2.0;
  const auto held = rest.back();
  SUBCASE("default: the stand sizes the body, the grips are not taken from it") {
    Feeder f;
    f.feed(table);
    REQUIRE(f.r().status == features::CalibrationStatus::Calibrated);
    CHECK(f.r().eye_height == doctest::Approx(1.65).epsilon(0.002).scale(0));
    CHECK(f.r().grips_not_held >= 2);
    CHECK(f.r().grip_default[0]);
    CHECK(f.r().grip_default[1]);
    for (int k = 1; k <= 2; ++k)
      CHECK(f.cal.calibration().offset[k].angularDistance(features::DeviceModel::default_orientation_offset()) < 1e-12);
    CHECK(std::string(f.r().message).find("both grips not seen held: device model's") != std::string::npos);
    // picked up: the next stand at the same height is averaged in and gives the held grips
    f.feed(rest);
    CHECK(f.r().windows == 2);
    CHECK_FALSE(f.r().grip_default[0]);
    CHECK_FALSE(f.r().grip_default[1]);
    for (double e : grip_errors(f.cal.calibration(), held)) CHECK(e < 1e-3);
    CHECK(std::string(f.r().message).find("grip") == std::string::npos);
    // a later table stand does not undo them
    auto again = sparsebody_test::session({{Phase::Walk, 1.0, 1.65}, {Phase::Stand, 2.0, 1.65}});
    for (auto& fr : again) fr.time += 8.0;
    put_controllers_on_a_table(again);
    f.feed(again);
    CHECK(f.r().windows == 3);
    for (double e : grip_errors(f.cal.calibration(), held)) CHECK(e < 1e-3);
  }
  SUBCASE("max_grip_deviation = 0: taken from the table (the behaviour before)") {
    features::AutoCalibrationConfig cfg;
    cfg.max_grip_deviation = 0;
    Feeder f(cfg);
    f.feed(table);
    f.feed(rest);
    CHECK(f.r().grips_not_held == 0);
    for (double e : grip_errors(f.cal.calibration(), held)) CHECK(e == doctest::Approx(M_PI / 2).epsilon(1e-3));
  }
}

TEST_CASE("auto calibration: a 2.5 m giant is refused, the default body stays") {
  Feeder f;
  const double eye = 2.5 * 0.936;
  f.feed(sparsebody_test::session({{Phase::Stand, 2.0, eye}, {Phase::Walk, 1.0, eye}}));
  const auto& r = f.r();
  CHECK(r.status == features::CalibrationStatus::Refused);
  CHECK(r.refused == 1);
  CHECK(f.changes == 0);
  CHECK(f.cal.calibration().scale == 1.0);
  const std::string m = r.message;
  CHECK(m.find("refused") == 0);
  CHECK(m.find("2.50 m") != std::string::npos);
  CHECK(m.find("[1.20, 2.20] m") != std::string::npos);
}

TEST_CASE("auto calibration: no standing at all is the documented default body") {
  Feeder f;
  f.feed(sparsebody_test::session({{Phase::Walk, 10.0, 1.45}}));  // eyes below the default body's 1.46 m
  const auto& r = f.r();
  CHECK(f.changes == 0);
  CHECK_FALSE(r.sized_from_headset);
  CHECK(r.status == features::CalibrationStatus::Default);
  CHECK(r.source == features::CalibrationSource::None);
  CHECK(r.stature == doctest::Approx((kStdHead + 0.08) / 0.936));
  CHECK(f.cal.calibration().scale == 1.0);
  const Eigen::Quaterniond half = features::DeviceModel::default_orientation_offset();
  for (int k = 0; k < 4; ++k) CHECK(f.cal.calibration().offset[k].angularDistance(half) < 1e-12);
  CHECK((f.cal.calibration().position_offset[0] - Eigen::Vector3d(0, 0.08, 0.10)).norm() == 0.0);
  CHECK((f.cal.calibration().position_offset[1] - Eigen::Vector3d(0, -0.08, 0.03)).norm() == 0.0);
  CHECK(std::string(r.message).find("no standing frame yet: default body (stature") == 0);
}

TEST_CASE("auto calibration: before any stand the default body is no smaller than the headset shows") {
  // a tall user walking from frame 0: the body is sized to the first upright headset frame (a lower
  // bound on the stature, not a calibration), once; the first stand then refines it
  Feeder f;
  auto walk = sparsebody_test::session({{Phase::Walk, 3.0, 1.78}, {Phase::Stand, 2.0, 1.80}});
  const Eigen::Quaterniond tilt(Eigen::AngleAxisd(1.2, Eigen::Vector3d::UnitX()));  // the headset not on yet
  for (int i = 0; i < 5; ++i) walk[i].pose[0].orientation = trackers::to_xr(Eigen::Quaterniond(trackers::to_eigen(walk[i].pose[0].orientation) * tilt));
  walk[3].pose[0].position.y = std::numeric_limits<float>::quiet_NaN();  // and a NaN headset: not used either
  std::size_t i = 0;
  for (; i < 5; ++i) f.feed(walk[i]);
  CHECK(f.changes == 0);  // waits for an upright, finite headset
  CHECK(f.cal.calibration().scale == 1.0);
  const float eye0 = walk[5].pose[0].position.y;
  f.feed(walk[i++]);
  CHECK(f.changes == 1);
  CHECK(f.r().status == features::CalibrationStatus::Default);  // no calibration is claimed
  CHECK(f.r().source == features::CalibrationSource::None);
  CHECK(f.r().sized_from_headset);
  CHECK(f.cal.calibration().scale == doctest::Approx(kStdHead / (eye0 - 0.08)));
  CHECK(f.r().stature == doctest::Approx(eye0 / 0.936));
  CHECK(std::string(f.r().message).find("no standing frame yet: default body sized to the headset (stature >= ") == 0);
  CHECK(f.r().sized_lower_bound);
  for (; walk[i].time < 3.0; ++i) f.feed(walk[i]);
  CHECK(f.changes == 1);  // once: walking higher or lower later changes nothing
  for (; i < walk.size(); ++i) f.feed(walk[i]);
  CHECK(f.r().status == features::CalibrationStatus::Calibrated);
  CHECK_FALSE(f.r().sized_from_headset);
  CHECK(f.r().eye_height == doctest::Approx(1.80).epsilon(0.002).scale(0));
  CHECK(features::refines_size(f.cal.calibration().scale / (kStdHead / (eye0 - 0.08))));  // the stand refined it
  // recalibrate(): sized again from the next user's first frame
  f.cal.recalibrate();
  CHECK(f.cal.calibration().scale == 1.0);
  f.feed(sparsebody_test::session({{Phase::Walk, 1.0, 1.70}}));
  CHECK(f.r().sized_from_headset);
  CHECK(f.cal.calibration().scale == doctest::Approx(kStdHead / (1.70 - 0.08)).epsilon(0.01).scale(0));
  // seated (eyes at 1.20 m), above the plausible stature, or off: the default body
  for (int k = 0; k < 3; ++k) {
    features::AutoCalibrationConfig cfg;
    if (k == 2) cfg.size_from_headset = false;
    Feeder g(cfg);
    g.feed(sparsebody_test::session({{Phase::Walk, 2.0, k == 0 ? 1.20 : k == 1 ? 2.3 * 0.936 : 1.80}}));
    CHECK(g.changes == 0);
    CHECK(g.cal.calibration().scale == 1.0);
    CHECK_FALSE(g.r().sized_from_headset);
  }
  // an app floor that is not trusted (estimate_floor): the eye height is unknown, no sizing
  features::AutoCalibrationConfig cfg;
  cfg.estimate_floor = true;
  Feeder h(cfg);
  h.feed(sparsebody_test::session({{Phase::Walk, 2.0, 1.80}}));
  CHECK(h.cal.calibration().scale == 1.0);
}

TEST_CASE("auto calibration: size_from_headset_both_ways also shrinks the default body (QuestSim's avatar)") {
  for (const bool both : {false, true}) {
    features::AutoCalibrationConfig cfg;
    cfg.size_from_headset_both_ways = both;
    Feeder f(cfg);
    auto walk = sparsebody_test::session({{Phase::Walk, 2.0, 1.35}});  // eyes at 1.35 m: a ~1.44 m user (default 1.56 m)
    const float eye0 = walk[0].pose[0].position.y;
    f.feed(walk);
    CHECK(f.r().status == features::CalibrationStatus::Default);
    if (!both) {  // the kinematic pipelines keep the default (the lower bound says nothing)
      CHECK(f.changes == 0);
      CHECK_FALSE(f.r().sized_from_headset);
      CHECK(f.cal.calibration().scale == 1.0);
      continue;
    }
    CHECK(f.changes == 1);
    CHECK(f.r().sized_from_headset);
    CHECK_FALSE(f.r().sized_lower_bound);
    CHECK(f.r().stature == doctest::Approx(eye0 / 0.936));
    CHECK(f.cal.calibration().scale == doctest::Approx(kStdHead / (eye0 - 0.08)));
    CHECK(std::string(f.r().message).find("default body sized to the first upright headset frame (stature ~") != std::string::npos);
  }
  // below the plausible range (eyes at 1.0 m: 1.07 m): not used
  features::AutoCalibrationConfig cfg;
  cfg.size_from_headset_both_ways = true;
  Feeder g(cfg);
  g.feed(sparsebody_test::session({{Phase::Walk, 2.0, 1.0}}));
  CHECK(g.changes == 0);
  CHECK_FALSE(g.r().sized_from_headset);
}

TEST_CASE("auto calibration: NaN bursts and a lost headset break a window, no NaN comes out") {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int kind = 0; kind < 3; ++kind) {
    INFO("kind " << kind);
    Feeder f;
    // 2.5 s standing with a break every 0.8 s: never 1 s of consecutive still frames
    auto s = sparsebody_test::session({{Phase::Stand, 2.5, 1.65}});
    for (std::size_t i = 0; i < s.size(); ++i)
      if (i % 24 == 23) {
        if (kind == 0) s[i].pose[0].position.y = nan;
        if (kind == 1) s[i].valid[0] = false;
        if (kind == 2) s[i].pose[0].orientation = {nan, nan, nan, nan};
        if (kind == 0) s[i].pose[1].orientation.w = nan;  // also a NaN controller (ignored: not valid data)
      }
    f.feed(s);
    // 0.77 s stands: a provisional estimate only (first_window), never a confirmed one
    CHECK(f.r().status == features::CalibrationStatus::Calibrated);
    CHECK(f.r().provisional);
    CHECK(f.r().windows == 1);
    CHECK(finite(f.cal.calibration()));
    features::AutoCalibrationConfig strict;
    strict.first_window = 0;  // without the provisional estimate: the default body
    Feeder h(strict);
    h.feed(s);
    CHECK(h.r().status == features::CalibrationStatus::Default);
    // the same session without breaks calibrates
    Feeder g;
    g.feed(sparsebody_test::session({{Phase::Stand, 2.5, 1.65}}));
    CHECK(g.r().status == features::CalibrationStatus::Calibrated);
  }
  // a controller held up at the head (not standing relaxed) is no standing window either
  Feeder h;
  auto s = sparsebody_test::session({{Phase::Stand, 3.0, 1.65}});
  for (auto& fr : s) fr.pose[1].position.y = fr.pose[0].position.y - 0.05f;
  h.feed(s);
  CHECK(h.r().status == features::CalibrationStatus::Default);
}

TEST_CASE("auto calibration: a frame looking at the floor or tilted is not standing") {
  Feeder f;
  auto s = sparsebody_test::session({{Phase::Stand, 3.0, 1.65}});
  const Eigen::Quaterniond down(Eigen::AngleAxisd(-0.7, Eigen::Vector3d::UnitX()));  // pitched 40 deg down
  for (auto& fr : s) fr.pose[0].orientation = trackers::to_xr(Eigen::Quaterniond(trackers::to_eigen(fr.pose[0].orientation) * down));
  f.feed(s);
  CHECK(f.r().status == features::CalibrationStatus::Default);
}

TEST_CASE("auto calibration: recalibrate() forgets and searches again; explicit calibration stops the search") {
  Feeder f;
  f.feed(sparsebody_test::session({{Phase::Stand, 2.0, 1.80}, {Phase::Walk, 1.0, 1.80}}));
  REQUIRE(f.r().status == features::CalibrationStatus::Calibrated);
  f.cal.recalibrate();
  CHECK(f.r().status == features::CalibrationStatus::Default);
  CHECK(f.cal.calibration().scale == 1.0);
  f.feed(sparsebody_test::session({{Phase::Stand, 2.0, 1.55}, {Phase::Walk, 1.0, 1.55}}));  // another user
  CHECK(f.r().status == features::CalibrationStatus::Calibrated);
  CHECK(f.r().stature == doctest::Approx(1.55 / 0.936).epsilon(0.002).scale(0));
  // an explicit frame: used as given, no more automatic changes
  const auto one = sparsebody_test::session({{Phase::Stand, 0.1, 1.70}})[0];
  REQUIRE(f.cal.calibrate_from(one));
  CHECK(f.r().source == features::CalibrationSource::Explicit);
  CHECK(f.cal.calibration().scale == doctest::Approx(kStdHead / (1.70 - 0.08)));
  const int before = f.changes;
  f.feed(sparsebody_test::session({{Phase::Stand, 3.0, 1.90}}));
  CHECK(f.changes == before);
  CHECK(f.r().source == features::CalibrationSource::Explicit);
}

TEST_CASE("auto calibration: estimate_floor puts the floor under the standing eye height (stature assumed)") {
  features::AutoCalibrationConfig cfg;
  cfg.estimate_floor = true;
  Feeder f(cfg);
  auto s = sparsebody_test::session({{Phase::Stand, 2.0, 1.62}, {Phase::Walk, 1.0, 1.62}});
  for (auto& fr : s)
    for (auto& p : fr.pose) p.position.y += 0.9f;  // an app whose origin is at the waist
  f.feed(s);
  const auto& r = f.r();
  REQUIRE(r.status == features::CalibrationStatus::Calibrated);
  CHECK(r.floor_estimated);
  CHECK(r.floor == doctest::Approx(1.62 + 0.9 - 0.936 * 1.70).epsilon(0.002).scale(0));
  CHECK(r.stature == doctest::Approx(1.70));
  CHECK(std::string(r.message).find("floor estimated") != std::string::npos);
}

TEST_CASE("auto calibration: a standing eye height below 0.5 m means y = 0 is not the floor (OpenXR LOCAL space): estimated") {
  for (const double y0 : {0.0, -0.3, 0.45, 0.6}) {
    CAPTURE(y0);
    Feeder f;
    auto s = sparsebody_test::session({{Phase::Stand, 2.0, 1.62}, {Phase::Walk, 1.0, 1.62}});
    for (auto& fr : s)
      for (auto& p : fr.pose) p.position.y += static_cast<float>(y0 - 1.62);  // the head starts at y = y0
    f.feed(s);
    const auto& r = f.r();
    if (y0 >= 0.5) {  // eyes at 0.6 m: a plausible floor that gives an implausible stature, refused as before
      CHECK(r.status == features::CalibrationStatus::Refused);
      CHECK_FALSE(r.floor_estimated);
      continue;
    }
    REQUIRE(r.status == features::CalibrationStatus::Calibrated);
    CHECK(r.floor_estimated);
    CHECK(r.floor == doctest::Approx(y0 - 0.936 * 1.70).epsilon(0.002).scale(0));
    CHECK(r.stature == doctest::Approx(1.70));
    CHECK(std::string(r.message).find("y = 0 is not the floor") != std::string::npos);
    // a later stand on the same estimated floor refines it; recalibrate() trusts y = 0 again
    f.cal.recalibrate();
    CHECK_FALSE(f.r().floor_estimated);
  }
  features::AutoCalibrationConfig off;
  off.floor_fallback_eye = 0;
  Feeder g(off);
  auto s = sparsebody_test::session({{Phase::Stand, 2.0, 1.62}, {Phase::Walk, 1.0, 1.62}});
  for (auto& fr : s)
    for (auto& p : fr.pose) p.position.y -= 1.62f;
  g.feed(s);
  CHECK(g.r().status == features::CalibrationStatus::Refused);  // as before, when turned off
}

TEST_CASE("LoBSTr pipeline: automatic by default, the calibration change restarts the feature history") {
  using P = avatar::LoBSTrPipeline<float, 32, 16>;
  static auto w = P::load(std::string(SPARSEBODY_SOURCE_DIR) + "/tests/pipeline/golden/lobstr_pipeline_small.weights.json");
  P p(w);
  CHECK(p.calibration_report().status == features::CalibrationStatus::Default);
  CHECK(p.user_scale() == 1.0);
  const auto s = sparsebody_test::session({{Phase::Walk, 2.0, 1.75}, {Phase::Stand, 2.5, 1.75}, {Phase::Walk, 2.0, 1.75}});
  bool changed_seen = false;
  for (const auto& f : s) {
    const auto before = p.calibration_report().status;
    p.push(f);
    if (before != p.calibration_report().status) {
      changed_seen = true;
      // the frame the calibration changed on: velocity features restarted at zero (no spike)
      for (int k = 0; k < 3; ++k) CHECK(p.features()[k] == 0.0f);
      for (int k = 0; k < 3; ++k) CHECK(p.features()[9 + k] == 0.0f);
    }
  }
  CHECK(changed_seen);
  CHECK(p.calibration_report().status == features::CalibrationStatus::Calibrated);
  CHECK(p.user_scale() == doctest::Approx((1.75 - 0.08) / p.meta().standing_head_height).epsilon(0.003).scale(0));
  p.recalibrate();
  CHECK(p.calibration_report().status == features::CalibrationStatus::Default);
  CHECK(p.user_scale() == 1.0);
  for (const auto& f : s) {
    trackers::TrackerFrame g = f;
    g.time += 10.0;
    p.push(g);
  }
  CHECK(p.calibration_report().status == features::CalibrationStatus::Calibrated);
}

TEST_CASE("LoBSTr pipeline: a bent first stand is raised when the user walks upright (sized, belt re-set, finite)") {
  using P = avatar::LoBSTrPipeline<float, 32, 16>;
  static auto w = P::load(std::string(SPARSEBODY_SOURCE_DIR) + "/tests/pipeline/golden/lobstr_pipeline_small.weights.json");
  P p(w);
  // crouched and still at 1.55 m first (belt at 0.93 m), then walking upright at 1.72 m (belt 1.03 m)
  const auto s = sparsebody_test::session({{Phase::Stand, 2.0, 1.55}, {Phase::Walk, 3.0, 1.72}});
  int outputs = 0;
  for (const auto& f : s) {
    p.push(f);
    if (!p.has_output()) continue;
    ++outputs;
    bool finite_pose = true;
    for (const auto& x : p.world().position) finite_pose &= x.allFinite();
    REQUIRE(finite_pose);
  }
  CHECK(outputs > 100);
  const auto& r = p.calibration_report();
  CHECK(r.raised == 1);
  CHECK(r.eye_height == doctest::Approx(1.70).epsilon(0.004).scale(0));  // the walk's lowest head: 1.72 less its 2 cm bob
  CHECK(p.user_scale() == doctest::Approx((r.eye_height - 0.08) / p.meta().standing_head_height).epsilon(1e-9).scale(0));
  // the belt re-set at the walk's mean pelvis height: there it is the standard standing hips height
  trackers::PoseD belt;
  belt.position = trackers::to_eigen(s.back().pose[3].position);
  belt.orientation = trackers::to_eigen(s.back().pose[3].orientation);
  CHECK(p.calibration().apply(3, belt).position.y() == doctest::Approx(p.meta().standing_hips_height).epsilon(0.01).scale(0));
}

TEST_CASE("LoBSTr pipeline: a calibration that barely changes the size keeps the feet where they are on the floor") {
  using P = avatar::LoBSTrPipeline<float, 256, 128>;
  static auto w = P::load(std::string(SPARSEBODY_SOURCE_DIR) + "/examples/weights/lobstr_compact.weights.json");
  // eye 1.50 m: s = 1.378 / 1.42 = 0.97 against the default body's 1 (a refinement-sized change);
  // eye 1.80 m: sized to the headset on the first frame, then refined by the stand
  for (double eye : {1.50, 1.80}) {
    INFO("eye height " << eye);
    P p(w);
    const auto s = sparsebody_test::session({{Phase::Stand, 3.0, eye}, {Phase::Walk, 1.0, eye}});
    ToeSteps toes(p);
    bool changed = false;
    double jump = 0;
    for (const auto& f : s) {
      const auto before = p.calibration_report().status;
      p.push(f);
      if (!p.has_output()) continue;
      const auto d = toes.next(p);
      if (d && before != p.calibration_report().status) {
        changed = true;
        jump = std::max({jump, (*d)[0], (*d)[1]});
      }
      REQUIRE(p.world().position[toes.toe[0]].allFinite());
    }
    REQUIRE(changed);
    MESSAGE("toe jump on the calibration frame: " << jump << " m (user scale " << p.user_scale() << ")");
    // within 5 %: the locks move with the rescaled world (no jump). The 1.80 m eye height is 20 %
    // off the default body, but the body was sized to the headset on the first frame, so the stand
    // refines it as well (before that sizing, this case restarted everything and the feet moved).
    CHECK(jump < 0.01);
  }
}

// Standing still after walking (issue 12: feet <= 1 cm/s), LoBSTr with the shipped weights: a session
// that walks from frame 0 (default body), stops within one frame and stands 4 s (the first
// calibration is found in that stand), then walks on. From 0.8 s into the stand both feet are held
// and the toes do not move; without the stillness hold they creep. The stillness detector's stop
// test holds the feet 0.1 s after the stop (the network otherwise walks on for a step), so the toes
// travel less in the stand's first 0.8 s than with the low-pass entry alone. The first calibration
// restarts the GRU (the body's size changes by more than 5 %) but the feet stay where they were
// shown (FootLock::lock_in_place): before that they snapped ~4 cm to the restarted network's stance.
TEST_CASE("LoBSTr pipeline: after walking, the feet stay put while the user stands, through the first calibration") {
  using P = avatar::LoBSTrPipeline<float, 256, 128>;
  static auto w = P::load(std::string(SPARSEBODY_SOURCE_DIR) + "/examples/weights/lobstr_compact.weights.json");
  const auto s = sparsebody_test::session({{Phase::Walk, 2.0, 1.62}, {Phase::Stand, 4.0, 1.62}, {Phase::Walk, 1.0, 1.62}});
  struct Result { double still_speed = 0, calib_jump = 0, stop_travel = 0; int held = 0, n = 0; bool calibrated_in_stand = false; };
  auto run = [&](bool hold, double stop_seconds = trackers::StillnessConfig{}.stop_seconds) {
    avatar::LoBSTrConfig c;
    c.hold_feet_when_still = hold;
    c.stillness.stop_seconds = stop_seconds;
    P p(w, c);
    ToeSteps toes(p);
    Result r;
    for (const auto& f : s) {
      const auto before = p.calibration_report().status;
      p.push(f);
      if (!p.has_output()) continue;
      const auto d = toes.next(p);
      const bool calibrated_now = before != p.calibration_report().status;
      if (calibrated_now && f.time > 2.0 && f.time < 6.0) r.calibrated_in_stand = true;
      if (d && calibrated_now) r.calib_jump = std::max({r.calib_jump, (*d)[0], (*d)[1]});
      if (d && f.time > 2.0 && f.time <= 2.8) r.stop_travel += (*d)[0] + (*d)[1];
      if (d && f.time > 2.8 && f.time < 6.0) {
        r.still_speed += ((*d)[0] + (*d)[1]) * 30.0 / 2;  // mean of the two toes, m/s at 30 Hz
        r.held += p.foot_locked(0) && p.foot_locked(1);
        ++r.n;
      }
    }
    REQUIRE(r.n > 60);
    r.still_speed /= r.n;
    return r;
  };
  const Result held = run(true), free = run(false), slow = run(true, 0.0);
  MESSAGE("LoBSTr standing after walking: toes " << 100 * held.still_speed << " cm/s held (" << held.held << "/" << held.n
          << " frames both feet locked), " << 100 * free.still_speed << " cm/s without the hold; toe jump on the calibration frame "
          << 100 * held.calib_jump << " cm; toe travel in the stand's first 0.8 s " << 100 * held.stop_travel << " cm ("
          << 100 * slow.stop_travel << " cm without the stop test)");
  CHECK(held.stop_travel < slow.stop_travel);
  CHECK(held.calibrated_in_stand);
  CHECK(held.still_speed < 0.01);
  CHECK(held.held == held.n);
  CHECK(held.still_speed < free.still_speed);
  CHECK(held.calib_jump < 0.005);
}

namespace {
// The user looks down by `degrees` through the frames: the headset pitched about the head joint (the
// headset less the device model's eye offset, turned with it, stays put).
void look_down(std::vector<trackers::TrackerFrame>& frames, double degrees) {
  const Eigen::Vector3d e = features::DeviceModel::default_orientation_offset() * features::DeviceModel{}.eye;  // headset frame
  for (auto& f : frames) {
    const Eigen::Quaterniond q = trackers::to_eigen(f.pose[0].orientation);
    const Eigen::Vector3d joint = trackers::to_eigen(f.pose[0].position) - q * e;
    const Eigen::Quaterniond down = q * Eigen::Quaterniond(Eigen::AngleAxisd(-degrees * M_PI / 180, Eigen::Vector3d::UnitX()));
    f.pose[0] = {trackers::to_xr(down), trackers::to_xr(Eigen::Vector3d(joint + down * e))};
  }
}
// The calibrated head's tilt from level at a frame (deg): what the networks see of it.
double head_tilt(const features::Calibration& c, const trackers::TrackerFrame& f) {
  const Eigen::Matrix3d R = (trackers::to_eigen(f.pose[0].orientation) * c.offset[0]).toRotationMatrix();
  return std::acos(std::clamp(R(1, 1), -1.0, 1.0)) * 180 / M_PI;
}
}  // namespace

TEST_CASE("auto calibration: a user looking down at the controllers through the stand gets a level head and the upright size") {
  auto stand = sparsebody_test::session({{Phase::Stand, 2.0, 1.65}});
  const auto level = stand.back();  // the same user looking ahead
  look_down(stand, 25);
  SUBCASE("level_head (default): the headset's offset is the device model's, the eye height the upright one") {
    Feeder f;
    f.feed(stand);
    REQUIRE(f.r().status == features::CalibrationStatus::Calibrated);
    CHECK(f.r().eye_height == doctest::Approx(1.65).epsilon(0.002).scale(0));  // the headset itself is ~5 cm lower
    CHECK(head_tilt(f.cal.calibration(), level) < 1e-6);                         // looking ahead: level
    CHECK(head_tilt(f.cal.calibration(), stand.back()) == doctest::Approx(25).epsilon(1e-6));
  }
  SUBCASE("level_head = false: the head looking down is taken for level (the behaviour before)") {
    features::AutoCalibrationConfig cfg;
    cfg.level_head = false;
    Feeder f(cfg);
    f.feed(stand);
    REQUIRE(f.r().status == features::CalibrationStatus::Calibrated);
    CHECK(f.r().eye_height < 1.65 - 0.04);
    CHECK(head_tilt(f.cal.calibration(), level) == doctest::Approx(25).epsilon(1e-6));  // looking ahead reads 25 deg up
  }
  SUBCASE("a headset tilted less than level_head_min_tilt (10 deg): the window's offset (a mounting tilt is absorbed)") {
    auto slight = sparsebody_test::session({{Phase::Stand, 2.0, 1.65}});
    look_down(slight, 6);
    Feeder f;
    f.feed(slight);
    REQUIRE(f.r().status == features::CalibrationStatus::Calibrated);
    CHECK(head_tilt(f.cal.calibration(), slight.back()) < 1e-6);
    CHECK(f.r().eye_height == doctest::Approx(1.65).epsilon(0.002).scale(0));  // still the upright eye height
  }
}
