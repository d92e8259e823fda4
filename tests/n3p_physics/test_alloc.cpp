// Zero heap allocations per 30 Hz physics frame (direct step, controller, tracker correction, 4
// simulation steps, fall check, output) over clean input, bad input and fall resets, and per
// simulation step alone.
#include <doctest/doctest.h>

#include <limits>

#include "n3p_physics/common.hpp"
#include "support/alloc_counter.hpp"
#include "support/standing_stream.hpp"

using namespace sparsebody;

TEST_CASE("n3p physics: no allocation per frame (with and without a target correction)") {
  using n3p_physics_test::Physics;
  const auto correction = Physics::load_correction(
      n3p_physics_test::write_correction_policy(std::string(SPARSEBODY_TEST_TMP) + "/alloc_correction.json", 0.3, 0.2));
  for (int run = 0; run < 4; ++run) {
    const int falls = run % 2;
    CAPTURE(run);
    avatar::N3PPhysicsConfig c;
    if (falls) c.fall.min_height = 5.0;  // every frame resets the character
    Physics p(n3p_physics_test::weights(), c);
    if (run >= 2) p.set_correction_policy(correction);
    p.set_calibration({});  // synthetic users: trackers at the joints, body convention
    std::vector<trackers::TrackerFrame> frames;
    for (int t = 0; t < 240; ++t) frames.push_back(n3p_physics_test::user_frame(t, 1.0));
    frames[40].pose[0].position.x = std::numeric_limits<float>::quiet_NaN();
    for (int t = 60; t < 70; ++t) frames[t].valid[0] = false;
    for (int t = 80; t < 120; ++t) frames[t].valid[1] = false;
    for (int t = 150; t < 240; ++t) frames[t].pose[0].position.x += 4.0f;  // jump -> physics restart
    for (int t = 0; t < 6; ++t) p.push(frames[t]);  // warm-up
    long long n = 0;
    {
      sparsebody_test::AllocationCounter counter;
      for (std::size_t t = 6; t < frames.size(); ++t) {
        trackers::TrackerFrame f = frames[t];
        f.time += 0.004;
        p.push(f);
      }
      n = counter.count();
    }
    CHECK(n == 0);
    CHECK(p.has_output());
    if (falls) CHECK(p.falls() > 100);
    if (run >= 2) CHECK(p.corrections() > 100);
  }
}

TEST_CASE("n3p physics: no allocation per simulation step (controller + correction + step)") {
  using n3p_physics_test::Physics;
  Physics p(n3p_physics_test::weights());
  p.set_calibration({});  // synthetic users: trackers at the joints, body convention
  const auto& m = p.model();
  dynamics::Simulator<float, 24, 72> sim(m);
  control::ModelBasedController<float, 24, 72> ctl(m);
  control::TrackerCorrection<float, 24, 72> tc(m);
  auto q0 = m.neutral_configuration();
  q0(1) += 0.01f;
  const double contact[2] = {1, 1};
  ctl.config().stance_support = true;
  Physics::VecV tau = Physics::VecV::Zero(m.nv);
  const dynamics::Vec3<float> target[2] = {dynamics::Vec3<float>(0.5f, 1.2f, 0.3f), dynamics::Vec3<float>(-0.5f, 1.2f, 0.3f)};
  const bool present[2] = {true, true};
  long long n = 0;
  {
    sparsebody_test::AllocationCounter counter;
    for (int k = 0; k < 120; ++k) {
      if (k % 4 == 0) ctl.set_reference(m, q0, q0, q0, 1.0f / 30, contact);
      ctl.apply(m, sim, (k % 4 + 1) / 4.0f, tau);
      tc.apply(m, sim.data(), target, present, tau);
      sim.torques() = tau;
      sim.step(1.0f / 120);
      ctl.residual_applied(sim);
    }
    n = counter.count();
  }
  CHECK(n == 0);
}

// The automatic calibration inside push(): a standing window found mid-stream changes the
// calibration, which restarts the physics (the reference changes size): at the first stand
// twice (its provisional estimate, then the whole window); nothing allocates.
TEST_CASE("n3p physics: automatic calibration restarts the physics and allocates nothing") {
  using n3p_physics_test::Physics;
  using sparsebody_test::Phase;
  const auto frames = sparsebody_test::session({{Phase::Walk, 1.0, 1.70}, {Phase::Stand, 2.5, 1.70}, {Phase::Walk, 1.0, 1.70},
                                                {Phase::Stand, 2.5, 1.60}, {Phase::Walk, 1.0, 1.60}},
                                               72.0, 0.3, false);
  Physics p(n3p_physics_test::weights());
  for (int t = 0; t < 6; ++t) p.push(frames[static_cast<std::size_t>(t)]);
  const long long restarts = p.restarts();
  long long n = 0;
  {
    sparsebody_test::AllocationCounter counter;
    for (std::size_t t = 6; t < frames.size(); ++t) p.push(frames[t]);
    n = counter.count();
  }
  CHECK(n == 0);
  CHECK(p.calibration_report().status == features::CalibrationStatus::Calibrated);
  CHECK(p.calibration_report().skipped == 1);
  CHECK(p.restarts() == restarts + 2);  // the provisional estimate after 0.5 s of the stand, then its whole window
  CHECK(p.has_output());
  CHECK(n3p_physics_test::finite_output(p));
}
