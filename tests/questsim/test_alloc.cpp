// A QuestSim control tick (sanitiser, window, observation, policy, 2 substeps, fall check, resets)
// never allocates: counted with a replaced global operator new.
#include "questsim/common.hpp"
#include "sparsebody/avatar/questsim_session.hpp"
#include "support/alloc_counter.hpp"

using namespace sparsebody;
using namespace sparsebody::control;
using namespace sparsebody::avatar;
using questsim_test::user_frame;

template <class C>
static void check_no_alloc() {
  C c(C::load_weights(questsim_test::policy_path()), 1.62);
  for (int k = 0; k < 20; ++k) c.push(user_frame(k / 72.0));  // warm up
  long long n = 0;
  int ticks = 0;
  {
    sparsebody_test::AllocationCounter counter;
    for (int k = 20; k < 20 + 4 * 72; ++k) {
      trackers::TrackerFrame f = user_frame(k / 72.0);
      if (k % 50 == 0) f.pose[1].position.x = std::nanf("");   // bad input
      if (k > 150 && k < 230) f.valid[0] = false;               // headset lost > 0.5 s: reset
      ticks += c.push(f);
      if (k == 100) c.simulator().options.velocity_limit = 1e-6;        // one simulation failure
      if (k == 102) c.simulator().options.velocity_limit = 500;
    }
    n = counter.count();
  }
  MESSAGE("ticks " << ticks << ", falls " << c.falls() << ", failures " << c.simulation_failures() << ", resets "
                   << c.tracker_resets());
  CHECK(ticks >= 140);
  CHECK(c.simulation_failures() >= 1);
  CHECK(c.tracker_resets() >= 1);
  CHECK(n == 0);
}

TEST_CASE("QuestSim control ticks do not allocate (float and double simulation, f16 and q8 policy)") {
  check_no_alloc<QuestSimDefault>();
  check_no_alloc<QuestSimDouble>();
  check_no_alloc<QuestSimF16>();
  check_no_alloc<QuestSimQ8>();
}

// The session front end: ticks, the automatic calibration resizing the avatar (a walk, then a
// stand of a 1.60 m user: the provisional estimate and its refinement), explicit calls.
TEST_CASE("QuestSim session: push, resizes and the calibration calls do not allocate") {
  QuestSimSessionDefault s(QuestSimSessionDefault::load(questsim_test::policy_path()));
  auto frame = [](double t, bool moving) {
    trackers::TrackerFrame f = user_frame(t, 1.60);
    if (!moving) {  // hold the head and hands still (a stand)
      f = user_frame(0, 1.60);
      f.time = t;
    }
    return f;
  };
  for (int k = 0; k < 20; ++k) s.push(frame(k / 72.0, true));  // warm up
  long long n = 0;
  {
    sparsebody_test::AllocationCounter counter;
    for (int k = 20; k < 20 + 3 * 72; ++k) s.push(frame(k / 72.0, k < 72));
    s.recalibrate();
    s.calibrate(frame(3.2, false));
    s.set_user_scale(1.1);
    for (int k = 0; k < 36; ++k) s.push(frame(3.3 + k / 72.0, true));
    s.reset();
    n = counter.count();
  }
  MESSAGE("resizes " << s.resizes() << ", stature " << s.calibration_report().stature);
  CHECK(s.resizes() >= 3);
  CHECK(n == 0);
}
