// Physics sanity: momentum conservation, energy drift, free fall of the COM, PD stability with
// implicit vs explicit damping, bad-state detection.
#include <doctest/doctest.h>

#include <cstdio>

#include "sparsebody/character/avatar.hpp"
#include "sparsebody/character/humanoid3d.hpp"
#include "sparsebody/dynamics/simulator.hpp"
#include "test_util.hpp"

using namespace sparsebody;
using namespace sparsebody::dynamics;

// World wrench sum_i X_0i^* (I a_i + v x* I v): the rate of change of total momentum.
template <class Model, class D>
static Vec6<double> momentum_rate(const Model& m, const D& d) {
  Vec6<double> r = Vec6<double>::Zero();
  for (int i = 0; i < m.nb; ++i) {
    const Vec6<double> f = m.bodies[i].I * d.a[i] + cross_force(d.v[i], Vec6<double>(m.bodies[i].I * d.v[i]));
    const Vec3<double> fw = d.R[i] * f.template tail<3>();
    r.head<3>() += d.R[i] * f.template head<3>() + d.p[i].cross(fw);
    r.tail<3>() += fw;
  }
  return r;
}

TEST_CASE("free-floating tree without gravity conserves momentum; energy drift is reported") {
  auto m = character::humanoid3d_like<double>(0.0, 0.0);
  m.gravity.setZero();
  Data<double, 16, 40> d(m);
  std::mt19937 rng(3);
  using Mo = decltype(m);
  Mo::VecQ q;
  Mo::VecV qd, qdd, tau = Mo::VecV::Zero(m.nv);
  double worst = 0;
  for (int t = 0; t < 200; ++t) {
    dyn_test::random_state(m, rng, q, qd, 3.0);
    dyn_test::aba_damped(m, d, q, qd, tau, qdd, 0.0);
    forward_kinematics(m, d, q, &qd);  // world poses (ABA itself does not need them)
    double scale = 0;
    for (int i = 0; i < m.nb; ++i) scale += (m.bodies[i].I * d.a[i]).norm();
    worst = std::max(worst, momentum_rate(m, d).norm() / scale);
  }
  std::printf("[physics] instantaneous momentum rate / force scale: %.2e\n", worst);
  CHECK(worst < 1e-9);

  // Integrated: spinning tree, semi-implicit Euler for 1 s; the drift must shrink like O(h).
  auto drift = [&](double h, double& max_dh, double& max_de) {
    Simulator<double, 16, 40> sim(m);
    sim.options.contacts_enabled = false;
    sim.options.mode = ControlMode::Torque;
    std::mt19937 r2(4);
    dyn_test::random_state(m, r2, q, qd, 2.0);
    sim.set_state(q, qd);
    const Vec6<double> h0 = spatial_momentum(m, sim.data());
    const double e0 = kinetic_energy(m, sim.data());
    max_dh = max_de = 0;
    for (int k = 0; k < int(1.0 / h + 0.5); ++k) {
      REQUIRE(sim.step(h) == StepStatus::Ok);
      max_dh = std::max(max_dh, (spatial_momentum(m, sim.data()) - h0).norm() / h0.norm());
      max_de = std::max(max_de, std::abs(kinetic_energy(m, sim.data()) - e0) / e0);
    }
  };
  double dh3, de3, dh4, de4;
  drift(1e-3, dh3, de3);
  drift(1e-4, dh4, de4);
  std::printf("[physics] spinning tree, 1 s: h=1e-3 momentum drift %.2e energy drift %.2e; h=1e-4 momentum %.2e energy %.2e\n",
              dh3, de3, dh4, de4);
  CHECK(de4 < 1e-3);
  CHECK(dh4 < 1e-3);
  CHECK(de3 / de4 > 5);  // first-order integrator: drift ~ h
  CHECK(dh3 / dh4 > 5);
}

TEST_CASE("with gravity and no contact the centre of mass falls at g") {
  const auto m = character::default_avatar<double>();
  Data<double, 24, 72> d(m);
  std::mt19937 rng(5);
  using Mo = std::decay_t<decltype(m)>;
  Mo::VecQ q;
  Mo::VecV qd, qdd, tau(m.nv);
  std::normal_distribution<double> n;
  double worst = 0;
  for (int t = 0; t < 200; ++t) {
    dyn_test::random_state(m, rng, q, qd);
    for (int k = 0; k < m.nv; ++k) tau(k) = k < 6 ? 0.0 : 30 * n(rng);  // internal torques only
    dyn_test::aba_damped(m, d, q, qd, tau, qdd, 1.0 / 120);
    forward_kinematics(m, d, q, &qd);
    Vec3<double> acc = Vec3<double>::Zero();
    for (int i = 0; i < m.nb; ++i) {
      const auto& b = m.bodies[i];
      Vec6<double> a = d.a[i];
      a.tail<3>() += d.R[i].transpose() * m.gravity;  // remove the fictitious base acceleration
      const Vec3<double> w = d.v[i].head<3>(), vo = d.v[i].tail<3>();
      const Vec3<double> ac = a.tail<3>() + a.head<3>().cross(b.com) + w.cross(vo + w.cross(b.com));
      acc += b.mass * (d.R[i] * ac);
    }
    acc /= m.total_mass();
    worst = std::max(worst, (acc - m.gravity).norm() / m.gravity.norm());
  }
  std::printf("[physics] COM acceleration vs g: max rel err %.2e\n", worst);
  CHECK(worst < 1e-10);

  // And integrated: COM(t) = c0 + v0 t + g t^2 / 2 within the O(h) error of Euler.
  Simulator<double, 24, 72> sim(m);
  sim.options.contacts_enabled = false;
  dyn_test::random_state(m, rng, q, qd, 0.5);
  sim.set_state(q, qd);
  const Vec3<double> c0 = center_of_mass(m, sim.data());
  Vec3<double> vc0 = Vec3<double>::Zero();
  for (int i = 0; i < m.nb; ++i) vc0 += m.bodies[i].mass * point_velocity(sim.data(), i, m.bodies[i].com);
  vc0 /= m.total_mass();
  const double h = 1e-3;
  for (int k = 0; k < 1000; ++k) REQUIRE(sim.step(h) == StepStatus::Ok);
  const Vec3<double> pred = c0 + vc0 + 0.5 * m.gravity;
  const double err = (center_of_mass(m, sim.data()) - pred).norm();
  std::printf("[physics] COM after 1 s free fall: error %.2e m (fall %.3f m)\n", err, 0.5 * 9.81);
  CHECK(err < 0.02);
}

// kp=200, kd=20, h=1/120, random targets every 0.5 s for 60 s, root welded, gravity on.
static double stability_run(bool implicit_damping, StepStatus& status, double& max_speed) {
  character::AvatarOptions o;
  o.fixed_root = true;
  const auto m = character::default_avatar<double>(o);
  Simulator<double, 24, 72> sim(m);
  sim.options.contacts_enabled = false;
  sim.options.implicit_damping = implicit_damping;
  sim.options.velocity_limit = 1e4;  // let the explicit run show its growth before it is stopped
  std::mt19937 rng(42);
  std::normal_distribution<double> n;
  max_speed = 0;
  status = StepStatus::Ok;
  const double h = 1.0 / 120;
  for (int k = 0; k < 60 * 120; ++k) {
    if (k % 60 == 0) {
      for (int i = 0; i < m.nb; ++i) {
        const auto& b = m.bodies[i];
        if (b.joint == JointType::Spherical)
          sim.set_target(i, quat_exp(Vec3<double>(0.5 * n(rng), 0.5 * n(rng), 0.5 * n(rng))));
        else if (b.joint == JointType::Revolute)
          sim.set_target(i, 0.7 * n(rng));
      }
    }
    status = sim.step(h);
    if (status != StepStatus::Ok) return k * h;
    max_speed = std::max(max_speed, sim.v().cwiseAbs().maxCoeff());
  }
  return 60.0;
}

TEST_CASE("kp=200 kd=20 at h=1/120: implicit damping stays bounded, explicit damping diverges") {
  StepStatus s_imp, s_exp;
  double v_imp, v_exp;
  const double t_imp = stability_run(true, s_imp, v_imp);
  const double t_exp = stability_run(false, s_exp, v_exp);
  std::printf("[stability] implicit: %.1f s simulated, status %s, max |qd| %.2f rad/s\n", t_imp, status_name(s_imp), v_imp);
  std::printf("[stability] explicit: failed after %.2f s, status %s, max |qd| before failure %.1f rad/s\n", t_exp,
              status_name(s_exp), v_exp);
  CHECK(t_imp == 60.0);
  CHECK(s_imp == StepStatus::Ok);
  CHECK(v_imp < 50.0);
  CHECK(t_exp < 60.0);
  CHECK(s_exp != StepStatus::Ok);
}

TEST_CASE("bad state is reported, not propagated") {
  const auto m = character::default_avatar<double>();
  Simulator<double, 24, 72> sim(m);
  auto q = sim.q();
  auto v = sim.v();
  v(7) = std::numeric_limits<double>::quiet_NaN();
  sim.set_state(q, v);
  CHECK(sim.step(1.0 / 120) == StepStatus::NonFiniteInput);
  v(7) = 1e6;  // exploding velocity
  sim.set_state(q, v);
  CHECK(sim.step(1.0 / 120) == StepStatus::VelocityLimit);
  CHECK(sim.v()(7) == 1e6);  // rolled back to the pre-step state
  CHECK(sim.q().allFinite());
}
