// Any body (pose/body_proportions.hpp): the standard skeleton re-proportioned by segment group, and
// the LoBSTr pipeline sizing its output's legs from the pelvis tracker's standing height.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <string>

#include "common.hpp"
#include "sparsebody/pose/body_proportions.hpp"
#include "support/standing_stream.hpp"

using namespace sparsebody;
using sparsebody_test::Phase;

namespace {
using Compact = avatar::LoBSTrCompact;
const std::shared_ptr<const Compact::Weights>& compact() {
  static auto w = Compact::load(SPARSEBODY_LOBSTR_WEIGHTS);
  return w;
}
// Standard-proportioned belt height / eye height for a user of eye height `eye` (the standard
// skeleton's hips / head heights, the eye 8 cm above the head joint: features/device_model.hpp).
double standard_belt_ratio(const predict::LoBSTrMeta& m, double eye) {
  const double s = m.standing_head_height / (eye - 0.08);
  return m.standing_hips_height / s / eye;
}
}  // namespace

TEST_CASE("body proportions: each segment group scaled by its ratio, nothing else; the head height kept") {
  Compact p(compact());
  const pose::Skeleton& s = p.standard_skeleton();
  pose::Skeleton out = s;
  pose::BodyProportions b;
  b.leg = 1.1, b.torso = 0.9, b.arm = 1.05;
  pose::apply_proportions(s, p.joint_map(), b, out);
  auto ratio = [&](const char* name) {
    const int j = s.find(name);
    REQUIRE(j >= 0);
    return out.offsets[j].norm() / s.offsets[j].norm();
  };
  for (const char* n : {"LowerLeg_L", "Foot_L", "Toes_L", "LowerLeg_R", "Foot_R", "Toes_R"}) CHECK(ratio(n) == doctest::Approx(1.1));
  for (const char* n : {"Spine", "Chest", "Neck", "Head", "Shoulder_L", "UpperArm_L", "Shoulder_R", "UpperArm_R", "UpperLeg_L",
                        "UpperLeg_R"})
    CHECK(ratio(n) == doctest::Approx(0.9));
  for (const char* n : {"LowerArm_L", "Hand_L", "LowerArm_R", "Hand_R"}) CHECK(ratio(n) == doctest::Approx(1.05));
  CHECK(out.offsets[0] == s.offsets[0]);
  // directions unchanged
  for (int j = 1; j < s.size(); ++j) CHECK(out.offsets[j].normalized().dot(s.offsets[j].normalized()) == doctest::Approx(1.0));
  // back to the standard proportions: the standard offsets exactly
  pose::apply_proportions(s, p.joint_map(), pose::BodyProportions{}, out);
  for (int j = 0; j < s.size(); ++j) CHECK(out.offsets[j] == s.offsets[j]);
  // the torso that keeps the head: r H_hips + t (H_head - H_hips) = H_head
  const double H = 0.908, Hh = 1.378;
  for (double r : {0.9, 1.0, 1.07}) {
    const double t = pose::BodyProportions::torso_for_legs(r, H, Hh);
    CHECK(r * H + t * (Hh - H) == doctest::Approx(Hh));
  }
}

TEST_CASE("LoBSTr pipeline: legs sized by the pelvis tracker's standing height, hips on it, feet on the floor") {
  const double eye = 1.75;
  const double standard = standard_belt_ratio(predict::LoBSTrMeta::from(compact()->info()), eye);
  struct Run {
    double leg, hips_gap, toe_max, toe_min;
  };
  // A stand (the calibration's window) then standing on: where the hips and the toes end up.
  auto run = [&](double belt_ratio, bool fit) {
    avatar::LoBSTrConfig cfg;
    cfg.fit_legs = fit;
    Compact p(compact(), cfg);
    const auto frames = sparsebody_test::session({{Phase::Stand, 4.0, eye, belt_ratio}}, 72.0);
    for (const auto& f : frames) p.push(f);
    REQUIRE(p.calibration_report().status == features::CalibrationStatus::Calibrated);
    REQUIRE(p.has_output());
    const double u = p.user_scale();
    const auto& w = p.world().position;
    const int hips = p.joint_map()[pose::Role::Hips], tl = p.joint_map()[pose::Role::ToeL], tr = p.joint_map()[pose::Role::ToeR];
    const double belt_y = frames.back().pose[3].position.y;
    return Run{p.body_proportions().leg, w[hips].y() * u - belt_y, std::max(w[tl].y(), w[tr].y()) * u,
               std::min(w[tl].y(), w[tr].y()) * u};
  };
  SUBCASE("long legs: 6 % above the standard proportions") {
    const Run a = run(standard * 1.06, true), b = run(standard * 1.06, false);
    CHECK(a.leg == doctest::Approx(1.06).epsilon(0.004));
    CHECK(std::abs(a.hips_gap) < 0.01);  // the hips at the belt (its joint: no offset in the device model)
    CHECK(b.hips_gap < -0.04);           // unfitted: at the standard hips height, ~6 cm under the belt
    CHECK(b.leg == 1.0);
    // the longer legs reach the floor from the higher hips
    CHECK(a.toe_min > -0.01);
    CHECK(a.toe_max < 0.10);
  }
  SUBCASE("short legs") {
    const Run a = run(standard * 0.94, true);
    CHECK(a.leg == doctest::Approx(0.94).epsilon(0.004));
    CHECK(std::abs(a.hips_gap) < 0.01);
    CHECK(a.toe_min > -0.01);
    CHECK(a.toe_max < 0.10);
  }
  SUBCASE("standard proportions give the standard skeleton") {
    const Run a = run(standard, true);
    CHECK(a.leg == doctest::Approx(1.0).epsilon(0.004));
  }
  SUBCASE("a belt far off the body's proportions is held to the limit") {
    CHECK(run(standard * 1.4, true).leg == doctest::Approx(1.12));
    CHECK(run(standard * 0.6, true).leg == doctest::Approx(0.88));
  }
}

TEST_CASE("LoBSTr pipeline: the output skeleton follows the calibration; standard without a pelvis tracker or a measured one") {
  const double eye = 1.75;
  const auto m = predict::LoBSTrMeta::from(compact()->info());
  const double belt = standard_belt_ratio(m, eye) * 1.06;
  Compact p(compact());
  const pose::Skeleton& out = p.skeleton();
  const int knee = p.joint_map()[pose::Role::LegL];
  const double thigh = p.standard_skeleton().offsets[knee].norm();
  CHECK(out.offsets[knee].norm() == thigh);  // the default body: standard
  for (const auto& f : sparsebody_test::session({{Phase::Stand, 4.0, eye, belt}}, 72.0)) p.push(f);
  CHECK(out.offsets[knee].norm() == doctest::Approx(1.06 * thigh).epsilon(0.004));  // the same object, re-proportioned
  CHECK(p.standard_skeleton().offsets[knee].norm() == thigh);
  p.recalibrate();  // the default body again until the next stand
  CHECK(out.offsets[knee].norm() == thigh);
  // explicit calibration without a hips height (trackers at the joints): standard
  features::Calibration c;
  c.scale = 0.9;
  p.set_calibration(c);
  CHECK(out.offsets[knee].norm() == thigh);
  // no pelvis tracker: nothing measures the legs
  Compact q(compact());
  for (const auto& f : sparsebody_test::session({{Phase::Stand, 4.0, eye, belt}}, 72.0, 0.3, false)) q.push(f);
  REQUIRE(q.calibration_report().status == features::CalibrationStatus::Calibrated);
  CHECK(q.body_proportions().standard());
  CHECK(q.skeleton().offsets[knee].norm() == thigh);
}

TEST_CASE("arm reach: raised to the least stretch of a run held for hold_time; glitches, lost sides and short stretches are not") {
  pose::ArmReachConfig cfg;  // margin 0.01, hold 0.2 s, limit 0.12
  const double dt = 1.0 / 30;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // e = |hand - shoulder| / L; not measured (or no arm length): NaN, which update() skips
  CHECK(pose::ArmReach::stretch(true, Eigen::Vector3d(0.3, 0.4, 0), Eigen::Vector3d::Zero(), 0.5) == doctest::Approx(1.0));
  CHECK(std::isnan(pose::ArmReach::stretch(false, Eigen::Vector3d(0.3, 0.4, 0), Eigen::Vector3d::Zero(), 0.5)));
  CHECK(std::isnan(pose::ArmReach::stretch(true, Eigen::Vector3d(0.3, 0.4, 0), Eigen::Vector3d::Zero(), 0.0)));
  SUBCASE("within the reach: nothing") {
    pose::ArmReach a(cfg);
    for (int i = 0; i < 100; ++i) CHECK_FALSE(a.update(1.0, 0.95, dt));
    CHECK(a.ratio() == 1.0);
  }
  SUBCASE("a stretch to 1.06 for 0.2 s on one side: the run's least") {
    pose::ArmReach a(cfg);
    int raised_at = -1;
    for (int i = 0; i < 10; ++i)
      if (a.update(0.9, i % 2 ? 1.06 : 1.07, dt) && raised_at < 0) raised_at = i;
    CHECK(raised_at == 5);  // the 6th frame completes 0.2 s
    CHECK(a.ratio() == doctest::Approx(1.06));
    // within the new reach + margin: no further change
    for (int i = 0; i < 30; ++i) CHECK_FALSE(a.update(1.065, nan, dt));
    CHECK(a.ratio() == doctest::Approx(1.06));
  }
  SUBCASE("a single stretched frame, or 0.17 s of them, is not enough; a lost controller ends a run") {
    pose::ArmReach a(cfg);
    for (int k = 0; k < 20; ++k) {
      for (int i = 0; i < 5; ++i) CHECK_FALSE(a.update(1.1, 1.1, dt));
      CHECK_FALSE(a.update(nan, nan, dt));
    }
    CHECK(a.ratio() == 1.0);
  }
  SUBCASE("held to 1 + limit; a controller further than any arm is not held; reset forgets; disabled never raises") {
    pose::ArmReach a(cfg);
    for (int i = 0; i < 30; ++i) a.update(1.2, 1.2, dt);
    CHECK(a.ratio() == doctest::Approx(1.12));
    a.reset();
    for (int i = 0; i < 90; ++i) CHECK_FALSE(a.update(1.5, 2.5, dt));  // both put down beyond 1.32
    CHECK(a.ratio() == 1.0);
    for (int i = 0; i < 6; ++i) a.update(2.5, 1.05, dt);  // one put down, the other stretched
    CHECK(a.ratio() == doctest::Approx(1.05));
    a.reset();
    CHECK(a.ratio() == 1.0);
    a.reset(0.9);  // from shorter arms an application gave: lengthened from there
    for (int i = 0; i < 6; ++i) a.update(0.95, nan, dt);
    CHECK(a.ratio() == doctest::Approx(0.95));
    pose::ArmReachConfig off = cfg;
    off.enabled = false;
    pose::ArmReach b(off);
    for (int i = 0; i < 30; ++i) CHECK_FALSE(b.update(1.5, 1.5, dt));
  }
}

TEST_CASE("LoBSTr pipeline: controllers held beyond the standard arm's reach lengthen the arms; the hands reach them") {
  const double eye = 1.75;
  auto run = [&](bool fit, double* hand_gap, double* arm) {
    avatar::LoBSTrConfig cfg;
    cfg.arm_reach.enabled = fit;
    Compact p(compact(), cfg);
    auto frames = sparsebody_test::session({{Phase::Stand, 3.0, eye}}, 30.0);
    sparsebody_test::reach_out(frames, 1.0, 0.56);
    for (const auto& f : frames) p.push(f);
    REQUIRE(p.calibration_report().status == features::CalibrationStatus::Calibrated);
    // the hand joints against where the calibrated controllers put the wrists (standard scale)
    double gap = 0;
    for (int side = 0; side < 2; ++side) {
      trackers::PoseD c;
      c.position = trackers::to_eigen(frames.back().pose[1 + side].position);
      c.orientation = trackers::to_eigen(frames.back().pose[1 + side].orientation);
      const Eigen::Vector3d target = p.calibration().apply(1 + side, c).position;
      const int hand = p.joint_map()[side == 0 ? pose::Role::HandL : pose::Role::HandR];
      gap = std::max(gap, (p.world().position[hand] - target).norm());
    }
    *hand_gap = gap;
    *arm = p.body_proportions().arm;
    return p.skeleton().offsets[p.skeleton().find("LowerArm_L")].norm() / p.standard_skeleton().offsets[p.skeleton().find("LowerArm_L")].norm();
  };
  double gap_fit, gap_std, arm_fit, arm_std;
  const double upper_ratio = run(true, &gap_fit, &arm_fit);
  run(false, &gap_std, &arm_std);
  CHECK(arm_std == 1.0);
  CHECK(gap_std > 0.02);  // the standard arm falls short of the controllers
  CHECK(arm_fit > 1.03);
  CHECK(arm_fit < 1.12);
  CHECK(upper_ratio == doctest::Approx(arm_fit));  // the skeleton's upper arm carries the ratio
  CHECK(gap_fit < 0.005);  // on them
  MESSAGE("arm ratio " << arm_fit << ", hands short of the controllers by " << gap_std << " m with the standard arms");
  Compact q(compact());
  auto frames = sparsebody_test::session({{Phase::Stand, 3.0, eye}}, 72.0);
  sparsebody_test::reach_out(frames, 1.0, 0.56, 72.0);
  for (const auto& f : frames) q.push(f);
  CHECK(q.body_proportions().arm > 1.03);  // at 72 Hz as well
  // controllers put down 1.2 m in front (on a table): no arm is that long, the arms stay standard
  Compact r(compact());
  frames = sparsebody_test::session({{Phase::Stand, 3.0, eye}}, 72.0);
  sparsebody_test::reach_out(frames, 3.0, 1.2, 72.0);
  for (const auto& f : frames) r.push(f);
  CHECK(r.body_proportions().arm == 1.0);
  // recalibrate(): a new user, the standard arms until they are seen again
  q.recalibrate();
  CHECK(q.body_proportions().arm == 1.0);
  CHECK(q.skeleton().offsets[q.skeleton().find("LowerArm_L")] == q.standard_skeleton().offsets[q.skeleton().find("LowerArm_L")]);
}

TEST_CASE("body lengths: a skeleton's proportions by leg length; an application's proportions override the belt's until recalibrate()") {
  Compact p(compact());
  const pose::Skeleton& s = p.standard_skeleton();
  const pose::BodyLengths std_len = pose::BodyLengths::of(s, p.joint_map());
  CHECK(std_len.leg == doctest::Approx(pose::leg_length(s, p.joint_map())));
  CHECK(std_len.torso == doctest::Approx(pose::rest_offset(s, s.find("Head"), 0).norm()));
  CHECK(std_len.arm == doctest::Approx(s.offsets[s.find("Hand_L")].norm() + s.offsets[s.find("LowerArm_L")].norm()));
  // a mocap skeleton in centimetres, half the size, torso x1.1 and arms x0.9 of the standard's
  pose::Skeleton user = s;
  pose::BodyProportions b;
  b.torso = 1.1, b.arm = 0.9;
  pose::apply_proportions(s, p.joint_map(), b, user);
  for (auto& o : user.offsets) o *= 50.0;
  const pose::BodyProportions got = pose::proportions_by_leg(pose::BodyLengths::of(user, p.joint_map()), std_len);
  CHECK(got.leg == 1.0);
  CHECK(got.torso == doctest::Approx(1.1));
  CHECK(got.arm == doctest::Approx(0.9));
  CHECK(pose::proportions_by_leg(pose::BodyLengths{}, std_len).standard());  // nothing to compare: standard
  CHECK(pose::arm_length(s, s.find("Hand_R")) == doctest::Approx(s.offsets[s.find("Hand_R")].norm() + s.offsets[s.find("LowerArm_R")].norm()));
  CHECK(pose::arm_length(s, 0) == 0.0);  // the root has no elbow
  CHECK(pose::arm_length(s, s.size()) == 0.0);
  // a length that is not a number (a malformed clip) gives 1 for that group, or standard when it is the leg
  const double nan = std::numeric_limits<double>::quiet_NaN();
  pose::BodyLengths bad = pose::BodyLengths::of(user, p.joint_map());
  bad.torso = nan;
  const pose::BodyProportions nt = pose::proportions_by_leg(bad, std_len);
  CHECK(nt.torso == 1.0);
  CHECK(nt.arm == doctest::Approx(0.9));
  bad.leg = nan;
  CHECK(pose::proportions_by_leg(bad, std_len).standard());
  bad = pose::BodyLengths::of(user, p.joint_map());
  bad.arm = std::numeric_limits<double>::infinity();
  CHECK(pose::proportions_by_leg(bad, std_len).arm == 1.0);
  CHECK(pose::proportions_by_leg(pose::BodyLengths::of(user, p.joint_map()), pose::BodyLengths{nan, nan, nan}).standard());
  // an application's proportions: held sane, used instead of the belt's estimate
  pose::BodyProportions wild;
  wild.leg = std::numeric_limits<double>::quiet_NaN(), wild.torso = 3.0, wild.arm = 0.9;
  p.set_body_proportions(wild);
  CHECK(p.body_proportions().leg == 1.0);
  CHECK(p.body_proportions().torso == 1.33);
  CHECK(p.body_proportions().arm == doctest::Approx(0.9));
  const int spine = s.find("Spine");
  CHECK(p.skeleton().offsets[spine].norm() == doctest::Approx(1.33 * s.offsets[spine].norm()));
  const auto m = predict::LoBSTrMeta::from(compact()->info());
  for (const auto& f : sparsebody_test::session({{Phase::Stand, 4.0, 1.75, standard_belt_ratio(m, 1.75) * 1.06}}, 72.0)) p.push(f);
  REQUIRE(p.calibration_report().status == features::CalibrationStatus::Calibrated);
  CHECK(p.body_proportions().leg == 1.0);  // the application's, not the belt's 1.06
  CHECK(p.body_proportions().torso == 1.33);
  p.recalibrate();  // a new user: the estimate again
  CHECK(p.body_proportions().standard());
}
