// The step never allocates: counted with a replaced global operator new.
#include <doctest/doctest.h>

#include "sparsebody/character/avatar.hpp"
#include "sparsebody/character/humanoid3d.hpp"
#include "sparsebody/dynamics/crba.hpp"
#include "sparsebody/dynamics/rnea.hpp"
#include "sparsebody/dynamics/simulator.hpp"
#include "support/alloc_counter.hpp"
#include "test_util.hpp"

using namespace sparsebody;
using namespace sparsebody::dynamics;

template <class S>
static void check_no_alloc(bool root_servo) {
  const auto m = character::default_avatar<S>();
  Simulator<S, 24, 72> sim(m);
  if (root_servo) {  // the root servo's implicit damping and bounded re-solves
    sim.options.root_servo.enabled = true;
    sim.options.root_servo.kp_linear = S(5000);
    sim.options.root_servo.kd_linear = S(1000);
    sim.options.root_servo.kp_angular = S(2000);
    sim.options.root_servo.kd_angular = S(200);
    sim.options.root_servo.max_force = S(300);
    sim.options.root_servo.max_torque = S(100);
  }
  auto q = sim.q();
  q(1) += S(0.005);  // feet just above the floor: contact candidates every step
  sim.set_state(q, sim.v());
  auto qdd = sim.v();
  auto tau = sim.v();
  Data<S, 24, 72> d(m);
  CrbaData<S, 24, 72> crba_out(m);
  long long n = 0;
  {
    sparsebody_test::AllocationCounter c;
    for (int k = 0; k < 240; ++k) {
      sim.set_target(m.find("UpperArm_L"), quat_exp(Vec3<S>(S(0.3), S(0), S(0.01) * S(k))));
      (void)sim.step(S(1.0 / 120));
    }
    dyn_test::aba_damped(m, d, sim.q(), sim.v(), tau, qdd, S(1.0 / 120));
    rnea(m, d, sim.q(), sim.v(), qdd, tau);
    crba(m, d, sim.q(), crba_out);
    n = c.count();
  }
  CHECK(sim.num_contacts() > 0);
  CHECK(n == 0);
}

TEST_CASE("step, ABA, RNEA and CRBA do not allocate (double and float, with and without the root servo)") {
  for (bool servo : {false, true}) {
    check_no_alloc<double>(servo);
    check_no_alloc<float>(servo);
  }
}
