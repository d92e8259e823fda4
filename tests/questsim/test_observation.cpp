// Observation layout and its frame-S properties (independent of the PyTorch reference).
#include <random>

#include "questsim/common.hpp"

using namespace sparsebody;
using namespace sparsebody::control;
using dynamics::Vec3;
using dynamics::Mat3;

TEST_CASE("QuestSim layout: sizes follow the model, paper numbers reproduced") {
  // Paper §3.3: 16 links, 33 DoF -> o_sim in R^312; §3.5 with 6 frames -> 162; plus the height.
  using Paper = QuestSimLayout<16, 33, 5>;
  CHECK(Paper::sim_size == 312);
  CHECK(Paper::size - Paper::sim_size - 1 == 162);
  CHECK(quest_sim_observation_size(16, 33, 5) == 475);
  // Default avatar, current + 6 future frames.
  using Av = QuestSimLayout<character::kDefaultAvatarBodies, character::kDefaultAvatarJointDofs, 6>;
  static_assert(Av::size == 607, "default avatar observation size");
  CHECK(Av::x == 96);
  CHECK(Av::f == 96 + 15 * 21);
  CHECK(Av::height == Av::size - 1);
  const auto m = character::default_avatar<double>();
  CHECK(m.nb == character::kDefaultAvatarBodies);
  CHECK(m.nv - 6 == character::kDefaultAvatarJointDofs);
  QuestSimObservationBuilder<double, 24, 72> ok(m);
  CHECK(ok.foot_of_body(m.find("Toes_R")) == 1);
  CHECK(ok.foot_of_body(m.find("Foot_L")) == 0);
  CHECK(ok.foot_of_body(m.find("Hand_L")) == -1);
  // A model of another shape is refused at construction (the layout would not fit).
  character::AvatarOptions o;
  o.hinge_knees_elbows = false;  // spherical knees/elbows: nv 62
  const auto m62 = character::default_avatar<double>(o);
  CHECK_THROWS_AS((QuestSimObservationBuilder<double, 24, 72>(m62)), std::invalid_argument);
  CHECK_NOTHROW((QuestSimObservationBuilder<double, 24, 72, 21, 56>(m62)));
}

namespace {
using Model = dynamics::Model<double, 24, 72>;
using Window = std::array<QuestSimSensorFrame<double>, 7>;
constexpr int NB = character::kDefaultAvatarBodies, NJ = character::kDefaultAvatarJointDofs;
using L = QuestSimLayout<NB, NJ, 6>;

struct State {
  Model::VecQ q;
  Model::VecV v;
  std::array<Vec3<double>, 2> f;
  Window user;
};

State random_state(const Model& m, std::mt19937& rng) {
  std::normal_distribution<double> n;
  State s;
  s.q = m.neutral_configuration();
  s.v = Model::VecV::Zero(m.nv);
  for (int i = 0; i < m.nb; ++i) {
    const auto& b = m.bodies[i];
    if (b.joint == dynamics::JointType::Spherical || b.joint == dynamics::JointType::Free) {
      const int k = b.q_index + (b.joint == dynamics::JointType::Free ? 3 : 0);
      const auto r = dynamics::quat_exp(Vec3<double>(0.4 * n(rng), 0.4 * n(rng), 0.4 * n(rng)));
      s.q(k) = r.w(); s.q(k + 1) = r.x(); s.q(k + 2) = r.y(); s.q(k + 3) = r.z();
    } else if (b.joint == dynamics::JointType::Revolute) {
      s.q(b.q_index) = 0.5 * n(rng);
    }
  }
  s.q(0) = n(rng); s.q(1) = 0.9 + 0.1 * n(rng); s.q(2) = n(rng);
  for (int k = 0; k < m.nv; ++k) s.v(k) = n(rng);
  s.f = {Vec3<double>(30 * n(rng), 300 + 30 * n(rng), 30 * n(rng)), Vec3<double>(30 * n(rng), 250 + 30 * n(rng), 30 * n(rng))};
  for (auto& fr : s.user)
    for (auto& d : fr) {
      d.position = Vec3<double>(n(rng), 1 + 0.3 * n(rng), n(rng));
      d.rotation = dynamics::quat_exp(Vec3<double>(n(rng), n(rng), n(rng))).toRotationMatrix();
    }
  return s;
}

std::array<double, L::size> observe(const Model& m, const State& s, double height) {
  dynamics::Data<double, 24, 72> d(m);
  dynamics::forward_kinematics(m, d, s.q, &s.v);
  std::array<double, L::size> o{};
  build_quest_sim_observation<NB, NJ, 6>(m, d, s.q, s.v, s.f, s.user, height, o.data());
  return o;
}
}  // namespace

TEST_CASE("QuestSim observation: invariant to a yaw rotation and horizontal shift of the whole scene (frame S)") {
  const Model m = character::default_avatar<double>();
  std::mt19937 rng(3);
  for (int trial = 0; trial < 20; ++trial) {
    const State a = random_state(m, rng);
    const auto oa = observe(m, a, 1.7);
    // Move everything: world' = Ry(psi) world + (tx, 0, tz).
    const double psi = 2.0 * trial - 17.0;
    const Mat3<double> G = Eigen::AngleAxisd(psi, Eigen::Vector3d::UnitY()).toRotationMatrix();
    const Vec3<double> t(1.3 - trial, 0, 0.2 * trial);
    State b = a;
    Eigen::Quaterniond r0(a.q(3), a.q(4), a.q(5), a.q(6));
    const Eigen::Quaterniond r1 = Eigen::Quaterniond(G) * r0;
    b.q.segment<3>(0) = G * a.q.segment<3>(0) + t;
    b.q(3) = r1.w(); b.q(4) = r1.x(); b.q(5) = r1.y(); b.q(6) = r1.z();
    for (int s = 0; s < 2; ++s) b.f[s] = G * a.f[s];
    for (int k = 0; k < 7; ++k)
      for (int dv = 0; dv < 3; ++dv) {
        b.user[k][dv].position = G * a.user[k][dv].position + t;
        b.user[k][dv].rotation = G * a.user[k][dv].rotation;
      }
    const auto ob = observe(m, b, 1.7);
    double err = 0;
    for (int i = 0; i < L::size; ++i) err = std::max(err, std::abs(oa[i] - ob[i]));
    CHECK(err < 1e-9);
    // The root sits above S's origin, and its forward axis (column 2 = col0 x col1) lies in S's
    // YZ plane: S carries the root's heading.
    CHECK(std::abs(oa[L::x + 0]) < 1e-12);
    CHECK(std::abs(oa[L::x + 2]) < 1e-12);
    CHECK(oa[L::x + 1] == doctest::Approx(a.q(1)));
    const Vec3<double> c0(oa[L::R], oa[L::R + 1], oa[L::R + 2]), c1(oa[L::R + 3], oa[L::R + 4], oa[L::R + 5]);
    CHECK(std::abs(c0.cross(c1).x()) < 1e-12);
    CHECK(oa[L::height] == 1.7);
  }
}

TEST_CASE("QuestSim observation: joint block holds rotation vectors, velocity block holds v without the root") {
  const Model m = character::default_avatar<double>();
  std::mt19937 rng(5);
  const State s = random_state(m, rng);
  const auto o = observe(m, s, 1.6);
  const int ua = m.find("UpperArm_L"), knee = m.find("LowerLeg_R");
  const auto& b = m.bodies[ua];
  const Eigen::Quaterniond q(s.q(b.q_index), s.q(b.q_index + 1), s.q(b.q_index + 2), s.q(b.q_index + 3));
  const Eigen::AngleAxisd aa(q);
  const Eigen::Vector3d rv = aa.angle() * aa.axis() * (aa.angle() > M_PI ? -1.0 : 1.0);
  for (int k = 0; k < 3; ++k) CHECK(o[L::q + b.v_index - 6 + k] == doctest::Approx(rv(k)).epsilon(1e-9));
  CHECK(o[L::q + m.bodies[knee].v_index - 6] == s.q(m.bodies[knee].q_index));
  for (int k = 0; k < NJ; ++k) CHECK(o[L::qd + k] == s.v(6 + k));
}
