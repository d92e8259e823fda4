// The simulator's root servo (root_servo.hpp): its damping is implicit in ABA like the joint servos',
// so stiff gains on the light pelvis are stable at h = 1/120 where the explicit form diverges;
// the wrench it applies never exceeds its bounds.
#include <doctest/doctest.h>

#include <cstdio>
#include <random>

#include "sparsebody/character/avatar.hpp"
#include "sparsebody/dynamics/simulator.hpp"

using namespace sparsebody;
using namespace sparsebody::dynamics;

namespace {
// The residual servo's gains of Neural3Points' default controller (model_based_controller.hpp).
void stiff_root_servo(RootServoOptions<double>& rs) {
  rs.enabled = true;
  rs.kp_linear = 5000;
  rs.kd_linear = 1000;
  rs.kp_angular = 2000;
  rs.kd_angular = 200;
}
// A random PD target (rotation vector ~ N(0, sigma) per axis) for every spherical joint.
template <class Sim, class Model>
void random_spherical_targets(Sim& sim, const Model& m, std::mt19937& rng, double sigma) {
  std::normal_distribution<double> n;
  for (int i = 0; i < m.nb; ++i)
    if (m.bodies[i].joint == JointType::Spherical)
      sim.set_target(i, quat_exp(Vec3<double>(sigma * n(rng), sigma * n(rng), sigma * n(rng))));
}

// Avatar in the air (no contacts) held by the root servo at its start pose, random joint targets
// every 0.5 s for 10 s. Returns the simulated time; worst root position error in `err`.
double hover_run(bool implicit_damping, StepStatus& status, double& err) {
  const auto m = character::default_avatar<double>();
  Simulator<double, 24, 72> sim(m);
  sim.options.contacts_enabled = false;
  sim.options.implicit_damping = implicit_damping;
  sim.options.velocity_limit = 1e4;
  stiff_root_servo(sim.options.root_servo);
  const auto q0 = sim.q();
  std::mt19937 rng(3);
  const double h = 1.0 / 120;
  err = 0;
  status = StepStatus::Ok;
  for (int k = 0; k < 10 * 120; ++k) {
    if (k % 60 == 0) random_spherical_targets(sim, m, rng, 0.4);
    status = sim.step(h);
    if (status != StepStatus::Ok) return k * h;
    err = std::max(err, (sim.data().p[0] - Vec3<double>(q0.head<3>())).norm());
  }
  return 10.0;
}
}  // namespace

TEST_CASE("root servo kp 5000 / kd 1000, 2000 / 200 at h=1/120: implicit damping holds the body, explicit diverges") {
  StepStatus s_imp, s_exp;
  double e_imp, e_exp;
  const double t_imp = hover_run(true, s_imp, e_imp);
  const double t_exp = hover_run(false, s_exp, e_exp);
  std::printf("[root-servo] implicit: %.1f s, %s, worst root error %.3f m; explicit: failed after %.2f s (%s)\n", t_imp,
              status_name(s_imp), e_imp, t_exp, status_name(s_exp));
  CHECK(t_imp == 10.0);
  CHECK(s_imp == StepStatus::Ok);
  CHECK(e_imp < 0.2);  // 63 kg on 5000 N/m sags 0.12 m; joint motion adds a little
  CHECK(t_exp < 10.0);
  CHECK(s_exp != StepStatus::Ok);
}

TEST_CASE("root servo: the applied wrench never exceeds its bounds, and reaches them") {
  const auto m = character::default_avatar<double>();
  Simulator<double, 24, 72> sim(m);
  auto& rs = sim.options.root_servo;
  stiff_root_servo(rs);
  rs.max_force = 400;
  rs.max_torque = 60;
  std::mt19937 rng(4);
  std::normal_distribution<double> n;
  double f_max = 0, n_max = 0;
  int at_f = 0, at_n = 0;
  for (int k = 0; k < 6 * 120; ++k) {
    if (k % 30 == 0) {  // joint targets and a root target that jump: large accelerations
      random_spherical_targets(sim, m, rng, 0.5);
      sim.targets()(0) = 0.03 * n(rng);
      sim.targets()(2) = 0.03 * n(rng);
    }
    REQUIRE(sim.step(1.0 / 120) == StepStatus::Ok);
    const double f = sim.root_servo_force().norm(), t = sim.root_servo_torque().norm();
    f_max = std::max(f_max, f);
    n_max = std::max(n_max, t);
    at_f += f > 0.999 * rs.max_force;
    at_n += t > 0.999 * rs.max_torque;
  }
  std::printf("[root-servo] bounds 400 N / 60 N m: max applied %.3f N / %.3f N m, at the bound on %d / %d of 720 steps\n", f_max,
              n_max, at_f, at_n);
  CHECK(f_max <= rs.max_force * (1 + 1e-9));
  CHECK(n_max <= rs.max_torque * (1 + 1e-9));
  CHECK(at_f > 0);
  CHECK(at_n > 0);
  // Off: nothing applied.
  rs.enabled = false;
  REQUIRE(sim.step(1.0 / 120) == StepStatus::Ok);
  CHECK(sim.root_servo_force().norm() == 0);
}
