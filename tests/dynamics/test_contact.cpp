// Contact: box rest and drift, slope slide vs stick around tan(slope), static boxes, avatar
// dropped lying down comes to rest without jitter. All at h = 1/120 s without substeps.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>

#include "sparsebody/character/avatar.hpp"
#include "sparsebody/dynamics/simulator.hpp"

using namespace sparsebody;
using namespace sparsebody::dynamics;

using BoxModel = Model<double, 2, 8>;
static BoxModel box_model(double mass = 1.0, double half = 0.1) {
  BoxModel m;
  Body<double> b;
  b.parent = -1;
  b.joint = JointType::Free;
  b.mass = mass;
  b.inertia = Mat3<double>::Identity() * (mass * (2 * half) * (2 * half) / 6.0);
  b.shapes[0].type = Shape<double>::Type::Box;
  b.shapes[0].half = Vec3<double>::Constant(half);
  b.num_shapes = 1;
  m.add_body("box", b);
  return m;
}

static double lowest_corner(const Simulator<double, 2, 8>& sim, const Vec3<double>& n, double offset) {
  double lo = 1e9;
  const auto& m = sim.model();
  for (int k = 0; k < m.num_points; ++k) lo = std::min(lo, n.dot(point_position(sim.data(), 0, m.points[k].pos)) - offset);
  return lo;
}

TEST_CASE("box dropped on the floor rests with < 5 mm penetration and no drift") {
  Simulator<double, 2, 8> sim(box_model());
  auto q = sim.q();
  auto v = sim.v();
  q.head<3>() = Vec3<double>(0, 0.5, 0);
  const Quat<double> r = quat_exp(Vec3<double>(0.3, 0.2, 0.1));
  q(3) = r.w(); q(4) = r.x(); q(5) = r.y(); q(6) = r.z();
  sim.set_state(q, v);
  const double h = 1.0 / 120;
  for (int k = 0; k < 3 * 120; ++k) REQUIRE(sim.step(h) == StepStatus::Ok);
  const Vec3<double> p1 = sim.q().head<3>();
  double max_speed = 0;
  for (int k = 0; k < 2 * 120; ++k) {
    REQUIRE(sim.step(h) == StepStatus::Ok);
    max_speed = std::max(max_speed, sim.v().norm());
  }
  const double pen = -lowest_corner(sim, Vec3<double>::UnitY(), 0.0);
  const double drift = (sim.q().head<3>() - p1).norm();
  std::printf("[contact] box at rest: penetration %.3f mm, drift over 2 s %.4f mm, max |v| %.2e, passes %d, contacts %d\n",
              pen * 1e3, drift * 1e3, max_speed, sim.last_passes(), sim.num_active_contacts());
  CHECK(pen < 0.005);
  CHECK(pen > -0.001);  // resting, not hovering
  CHECK(drift < 1e-4);
  CHECK(max_speed < 1e-3);
  CHECK(sim.num_active_contacts() == 4);
}

// Box placed flat on a plane tilted by `deg` about z; returns the distance travelled in 2 s and
// (in v0) the speed when the measurement starts.
static double slope_run(double deg, double mu, double* v0 = nullptr) {
  Simulator<double, 2, 8> sim(box_model());
  const double th = deg * M_PI / 180;
  const Quat<double> tilt(Eigen::AngleAxisd(th, Vec3<double>::UnitZ()));
  sim.env.ground_normal = tilt * Vec3<double>::UnitY();
  sim.options.contact.friction = mu;
  auto q = sim.q();
  q.head<3>() = sim.env.ground_normal * 0.1;  // resting on the plane
  q(3) = tilt.w(); q(4) = tilt.x(); q(5) = tilt.y(); q(6) = tilt.z();
  sim.set_state(q, sim.v());
  const double h = 1.0 / 120;
  for (int k = 0; k < 30; ++k) REQUIRE(sim.step(h) == StepStatus::Ok);  // settle
  const Vec3<double> p0 = sim.q().head<3>();
  if (v0) *v0 = point_velocity(sim.data(), 0, Vec3<double>(Vec3<double>::Zero())).norm();
  for (int k = 0; k < 2 * 120; ++k) REQUIRE(sim.step(h) == StepStatus::Ok);
  return (sim.q().head<3>() - p0).norm();
}

TEST_CASE("on a slope the box slides when mu < tan(slope) and sticks when mu > tan(slope)") {
  const double deg = 20, t = std::tan(deg * M_PI / 180);  // 0.364
  double v0 = 0;
  const double slide_far = slope_run(deg, 0.5 * t, &v0), slide_near = slope_run(deg, t - 0.05);
  const double stick_near = slope_run(deg, t + 0.05), stick_far = slope_run(deg, 2 * t);
  const double a_expected = 9.81 * (std::sin(deg * M_PI / 180) - 0.5 * t * std::cos(deg * M_PI / 180));
  const double d_expected = v0 * 2 + 0.5 * a_expected * 4;  // Coulomb sliding from speed v0
  std::printf("[contact] 20 deg slope, 2 s: mu=%.3f slid %.3f m (Coulomb: %.3f m), mu=%.3f slid %.3f m, "
              "mu=%.3f moved %.2f mm, mu=%.3f moved %.2f mm\n",
              0.5 * t, slide_far, d_expected, t - 0.05, slide_near, t + 0.05, stick_near * 1e3, 2 * t,
              stick_far * 1e3);
  CHECK(slide_far > 1.0);
  CHECK(std::abs(slide_far - d_expected) < 0.05 * d_expected);
  CHECK(slide_near > 0.1);
  CHECK(stick_near < 0.005);
  CHECK(stick_far < 0.005);
}

TEST_CASE("a box dropped on a static box rests on its top face") {
  Simulator<double, 2, 8> sim(box_model());
  StaticBox<double> table;
  table.center = Vec3<double>(0, 0.4, 0);
  table.half = Vec3<double>(0.5, 0.05, 0.5);
  sim.env.add_box(table);
  auto q = sim.q();
  q.head<3>() = Vec3<double>(0.1, 1.0, 0);
  sim.set_state(q, sim.v());
  for (int k = 0; k < 3 * 120; ++k) REQUIRE(sim.step(1.0 / 120) == StepStatus::Ok);
  const double y = sim.q()(1);
  std::printf("[contact] box on static box: centre height %.4f m (top face + half = 0.5500)\n", y);
  CHECK(std::abs(y - 0.55) < 0.005);
  CHECK(sim.v().norm() < 1e-3);
}

TEST_CASE("avatar dropped lying down comes to rest without jitter") {
  const auto m = character::default_avatar<double>();
  Simulator<double, 24, 72> sim(m);
  auto q = sim.q();
  const Quat<double> lie(Eigen::AngleAxisd(-M_PI / 2, Vec3<double>::UnitX()));  // on its back
  q.head<3>() = Vec3<double>(0, 0.3, 0);
  q(3) = lie.w(); q(4) = lie.x(); q(5) = lie.y(); q(6) = lie.z();
  sim.set_state(q, sim.v());
  const double h = 1.0 / 120;
  for (int k = 0; k < 4 * 120; ++k) REQUIRE(sim.step(h) == StepStatus::Ok);
  // Last second: largest speed of any body origin, and jitter (third difference of positions).
  double max_speed = 0, max_jerk = 0, min_height = 1e9;
  std::vector<std::vector<Vec3<double>>> hist;
  for (int k = 0; k < 120; ++k) {
    REQUIRE(sim.step(h) == StepStatus::Ok);
    std::vector<Vec3<double>> p(m.nb);
    for (int i = 0; i < m.nb; ++i) {
      p[i] = sim.data().p[i];
      max_speed = std::max(max_speed, point_velocity(sim.data(), i, Vec3<double>(Vec3<double>::Zero())).norm());
    }
    hist.push_back(p);
  }
  for (size_t k = 3; k < hist.size(); ++k)
    for (int i = 0; i < m.nb; ++i) {
      const Vec3<double> j3 = hist[k][i] - 3 * hist[k - 1][i] + 3 * hist[k - 2][i] - hist[k - 3][i];
      max_jerk = std::max(max_jerk, j3.norm() / (h * h * h));
    }
  for (int k = 0; k < sim.num_contacts(); ++k) {
    const auto& c = sim.contact_at(k);
    if (c.active) min_height = std::min(min_height, -c.depth);
  }
  std::printf("[contact] avatar lying: max body speed in the last second %.2e m/s, jitter (max |d3p/dt3|) %.2e m/s^3, "
              "%d active contacts, deepest %.2f mm, passes %d\n",
              max_speed, max_jerk, sim.num_active_contacts(), -min_height * 1e3, sim.last_passes());
  CHECK(max_speed < 0.01);
  CHECK(max_jerk < 1.0);
  CHECK(sim.num_active_contacts() >= 4);
  CHECK(-min_height < 0.005);
}

TEST_CASE("a contact solve cap below 1 still solves each step once (same result as a cap of 1)") {
  const auto m = character::default_avatar<double>();
  auto run = [&](int cap) {
    Simulator<double, 24, 72> sim(m);
    sim.options.contact.max_passes = cap;
    auto q = sim.q();
    q(1) += 0.005;  // feet just above the floor: contacts from the first step
    sim.set_state(q, sim.v());
    for (int k = 0; k < 120; ++k) REQUIRE(sim.step(1.0 / 120) == StepStatus::Ok);
    CHECK(sim.num_contacts() > 0);
    CHECK(sim.last_passes() == 1);
    return sim.q();
  };
  const auto q1 = run(1);
  for (int cap : {0, -3}) {
    const auto q = run(cap);
    CHECK((q - q1).cwiseAbs().maxCoeff() == 0.0);
  }
}
