// The QuestSim session (avatar/questsim_session.hpp): the avatar rescaled in place equals one built
// at that height, the automatic calibration sizes it to the user, the explicit calls, and the
// output on the avatar's skeleton.
#include "questsim/common.hpp"

#include "sparsebody/avatar/questsim_session.hpp"

using namespace sparsebody;
using namespace sparsebody::avatar;
using questsim_test::user_frame;

namespace {

// A user of `height` standing still at (0.3, -0.4), facing -Z, hands at the sides; moving (walking
// in place with the head bobbing 4 cm and the hands swinging) when `moving`.
trackers::TrackerFrame standing_frame(double t, double height, bool moving = false) {
  trackers::TrackerFrame f;
  f.time = t;
  const double bob = moving ? 0.04 * std::sin(2 * M_PI * 1.8 * t) : 0.002 * std::sin(1.3 * t);
  const Eigen::Vector3d head(0.3, 0.936 * height + bob, -0.4 + (moving ? 0.3 * t : 0.0));
  f.pose[0] = {questsim_test::yaw_pitch(0, 0), trackers::to_xr(head)};
  for (int side = 0; side < 2; ++side) {
    const double sx = side == 0 ? -1.0 : 1.0;
    const double swing = moving ? 0.2 * std::sin(2 * M_PI * 0.9 * t + M_PI * side) : 0.0;
    f.pose[1 + side] = {questsim_test::yaw_pitch(0, 0), trackers::to_xr(head + Eigen::Vector3d(sx * 0.2, -0.36 * height, swing))};
  }
  f.valid = {true, true, true, false};
  return f;
}

}  // namespace

TEST_CASE("QuestSim set_user_height rescales in place: bit-identical to a controller built at that height") {
  const auto w = questsim_test::policy_weights<QuestSimDefault>();
  QuestSimDefault rescaled(w, 1.75), built(w, 1.58);
  for (int k = 0; k < 36; ++k) rescaled.push(user_frame(k / 72.0, 1.75));  // it ran as another body first
  REQUIRE(rescaled.set_user_height(1.58));
  CHECK(rescaled.user_height() == doctest::Approx(1.58));
  CHECK(rescaled.torque_limits() == built.torque_limits());
  CHECK(rescaled.simulator().model().total_mass() == built.simulator().model().total_mass());
  // the same input from here on: the same simulation, bit for bit
  for (int k = 36; k < 36 + 3 * 72; ++k) {
    const trackers::TrackerFrame f = user_frame(k / 72.0, 1.58);
    CHECK(rescaled.push(f) == built.push(f));
  }
  REQUIRE(rescaled.steps() > 0);
  CHECK(rescaled.simulator().q() == built.simulator().q());
  CHECK(rescaled.simulator().v() == built.simulator().v());
  // a height the pipeline refuses changes nothing
  const auto q = rescaled.simulator().q();
  CHECK_FALSE(rescaled.set_user_height(0.5));
  CHECK_FALSE(rescaled.set_user_height(std::nan("")));
  CHECK(rescaled.user_height() == doctest::Approx(1.58));
  CHECK(rescaled.simulator().q() == q);
}

TEST_CASE("QuestSim session: sized from the first upright headset frame, then the stature of a stand") {
  QuestSimSessionDefault s(questsim_test::policy_weights<QuestSimDefault>());
  CHECK(s.user_scale() == doctest::Approx(1.0));
  CHECK(s.skeleton().size() == 21);
  CHECK(s.skeleton().names[0] == "Hips");
  CHECK(s.calibration_report().status == features::CalibrationStatus::Default);
  // the session starts with the user walking: no calibration from it, but the avatar takes the
  // first upright headset frame's stature (eyes at 0.936 x 1.60 m)
  double t = 0;
  for (; t < 2.0; t += 1 / 72.0) s.push(standing_frame(t, 1.60, true));
  CHECK(s.calibration_report().status == features::CalibrationStatus::Default);
  CHECK(s.calibration_report().sized_from_headset);
  CHECK(s.pipeline().user_height() == doctest::Approx(1.60).epsilon(0.005));
  CHECK(s.resizes() == 1);
  REQUIRE(s.has_output());
  // then stands still for 2.5 s: calibrated at 1.60 m (eye height / 0.936), avatar resized once
  for (const double t0 = t; t < t0 + 2.5; t += 1 / 72.0) s.push(standing_frame(t, 1.60));
  const features::CalibrationReport& r = s.calibration_report();
  CHECK(r.status == features::CalibrationStatus::Calibrated);
  CHECK(r.source == features::CalibrationSource::Automatic);
  CHECK(r.stature == doctest::Approx(1.60).epsilon(0.005));
  CHECK(s.pipeline().user_height() == doctest::Approx(r.stature).epsilon(0.01));
  CHECK(s.user_scale() == doctest::Approx(1.60 / 1.75).epsilon(0.01));
  CHECK(s.resizes() == 1);  // the stand agreed with the first frame's size within 1 cm
  // the output: the simulated bodies in skeleton units (x user_scale: metres), under the headset
  REQUIRE(s.has_output());
  const int head = s.joint_map()[pose::Role::Head];
  const Eigen::Vector3d head_m = s.user_scale() * s.world().position[static_cast<std::size_t>(head)];
  CHECK(head_m.allFinite());
  CHECK(std::hypot(head_m.x() - 0.3, head_m.z() + 0.4) < 0.35);
  CHECK(head_m.y() > 1.0);
  CHECK(head_m.y() < 1.65);
  // world() is the forward kinematics of pose() on the avatar's skeleton
  pose::WorldPose fk;
  fk.resize(s.skeleton().size());
  pose::forward_kinematics(s.skeleton(), s.pose(), fk);
  for (int j = 0; j < s.skeleton().size(); ++j) CHECK((fk.position[j] - s.world().position[j]).norm() < 1e-4);
  CHECK(s.output_time() == doctest::Approx(t - 1 / 72.0 - s.delay_seconds()).epsilon(0.02));
}

TEST_CASE("QuestSim session: explicit calibration, a refused frame, recalibrate, set_user_scale") {
  QuestSimSessionDefault s(questsim_test::policy_weights<QuestSimDefault>());
  for (int k = 0; k < 20; ++k) s.push(standing_frame(k / 72.0, 1.75, true));
  trackers::TrackerFrame low = standing_frame(0.3, 1.75);
  low.pose[0].position.y = 0.3f;  // headset on the floor: no height
  CHECK_FALSE(s.calibrate(low));
  CHECK(s.pipeline().user_height() == doctest::Approx(1.75));
  CHECK(s.calibration_report().status == features::CalibrationStatus::Default);
  REQUIRE(s.calibrate(standing_frame(0.3, 1.88)));
  CHECK(s.calibration_report().source == features::CalibrationSource::Explicit);
  CHECK(s.pipeline().user_height() == doctest::Approx(1.88).epsilon(0.01));
  // the search is off now: a stand of another height changes nothing
  for (double t = 0.3; t < 3.5; t += 1 / 72.0) s.push(standing_frame(t, 1.60));
  CHECK(s.pipeline().user_height() == doctest::Approx(1.88).epsilon(0.01));
  s.recalibrate();
  CHECK(s.pipeline().user_height() == doctest::Approx(1.75));
  CHECK(s.calibration_report().status == features::CalibrationStatus::Default);
  for (double t = 3.5; t < 6.5; t += 1 / 72.0) s.push(standing_frame(t, 1.60));
  CHECK(s.pipeline().user_height() == doctest::Approx(1.60).epsilon(0.01));
  REQUIRE(s.set_user_scale(1.75 / 1.70));
  CHECK(s.pipeline().user_height() == doctest::Approx(1.70));
  CHECK(s.calibration_report().source == features::CalibrationSource::Application);
  CHECK_FALSE(s.set_user_scale(0.1));  // 17.5 m
  CHECK(s.pipeline().user_height() == doctest::Approx(1.70));
}
