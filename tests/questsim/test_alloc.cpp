// A QuestSim control tick (sanitiser, window, observation, policy, 2 substeps, fall check, resets)
// never allocates: counted with a replaced global operator new.
#include "questsim/common.hpp"
#include "support/alloc_counter.hpp"

using namespace sparsebody;
using namespace sparsebody::control;
using questsim_test::userFrame;

template <class C>
static void checkNoAlloc() {
  C c(C::loadWeights(questsim_test::policyPath()), 1.62);
  for (int k = 0; k < 20; ++k) c.push(userFrame(k / 72.0));  // warm up
  long long n = 0;
  int ticks = 0;
  {
    sparsebody_test::AllocationCounter counter;
    for (int k = 20; k < 20 + 4 * 72; ++k) {
      trackers::TrackerFrame f = userFrame(k / 72.0);
      if (k % 50 == 0) f.pose[1].position.x = std::nanf("");   // bad input
      if (k > 150 && k < 230) f.valid[0] = false;               // headset lost > 0.5 s: reset
      ticks += c.push(f);
      if (k == 100) c.simulator().velocity_limit = 1e-6;        // one simulation failure
      if (k == 102) c.simulator().velocity_limit = 500;
    }
    n = counter.count();
  }
  MESSAGE("ticks " << ticks << ", falls " << c.falls() << ", failures " << c.simulationFailures() << ", resets "
                   << c.trackerResets());
  CHECK(ticks >= 140);
  CHECK(c.simulationFailures() >= 1);
  CHECK(c.trackerResets() >= 1);
  CHECK(n == 0);
}

TEST_CASE("QuestSim control ticks do not allocate (float and double simulation, f16 and q8 policy)") {
  checkNoAlloc<QuestSimController<float>>();
  checkNoAlloc<QuestSimController<double>>();
  checkNoAlloc<QuestSimController<float, nn::f16>>();
  checkNoAlloc<QuestSimController<float, nn::q8>>();
}
