// Any body (pose/body_proportions.hpp): the standard skeleton re-proportioned by segment group, and
// the LoBSTr pipeline sizing its output's legs from the pelvis tracker's standing height.
#include <doctest/doctest.h>

#include <cmath>
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
