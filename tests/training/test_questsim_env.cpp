// QuestSim training environment (training/questsim_env.hpp) on a synthetic clip of the standard
// skeleton (arms raised and lowered while standing): reference-state initialisation puts the
// retargeted reference on the floor under the headset, the same seed gives the same bits whatever the
// thread count, the residual force keeps a character up that falls without it, step() never
// allocates, and the action mapping is the run-time pipeline's.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>

#include "sparsebody/avatar/questsim.hpp"
#include "sparsebody/predict/n3p_predictor.hpp"
#include "sparsebody/training/questsim_env.hpp"
#include "support/alloc_counter.hpp"
#include "training/synthetic_clip.hpp"

using namespace sparsebody;
using Env = training::QuestSimEnv<6>;

namespace {

using training_test::meta;
using training_test::synthetic_clip;

std::shared_ptr<const std::vector<training::QuestSimReference>> clips() {
  static auto c = [] {
    auto v = std::make_shared<std::vector<training::QuestSimReference>>();
    v->push_back(training::make_questsim_reference(synthetic_clip(), meta().skeleton, "synthetic"));
    return v;
  }();
  return c;
}

std::vector<float> random_actions(int n, unsigned seed, float scale) {
  return training_test::random_actions<Env::kActionSize>(n, seed, scale);
}

}  // namespace

TEST_CASE("QuestSim reference: 36 Hz frames of the clip, the devices where a headset session would have them") {
  const auto& r = clips()->front();
  CHECK(r.frames() == doctest::Approx(36 * (119 / 30.0)).epsilon(0.02));
  for (const auto& s : r.sensor) {
    CHECK(s[0].position.y() > 1.3);          // headset at eye height
    CHECK(s[0].position.y() < 1.8);
    CHECK(std::abs(s[0].rotation.determinant() - 1.0) < 1e-9);
  }
}

TEST_CASE("QuestSim env: reference-state initialisation stands the avatar on the floor under the headset") {
  Env env(clips(), meta(), std::vector<double>(8, 1.75), 11);
  for (int i = 0; i < env.size(); ++i) {
    const auto& d = env.simulator(i).data();
    const auto& m = env.model(i);
    double lowest = 1e9;
    for (int b = 0; b < m.nb; ++b) lowest = std::min(lowest, double(d.p[b].y()));
    CHECK(lowest > -0.01);
    CHECK(lowest < 0.15);  // ankles / toes near the floor
    const int head = m.find("Head");
    const Eigen::Vector3d hs = env.sensor(i)[0].position;
    CHECK((d.p[head].cast<double>() - hs).norm() < 0.3);  // headset ~10 cm in front of / above the head joint
    const float* o = env.observations() + std::size_t(i) * Env::kObservationSize;
    for (int k = 0; k < Env::kObservationSize; ++k) REQUIRE(std::isfinite(o[k]));
    CHECK(o[Env::kObservationSize - 1] == doctest::Approx(1.75));  // o_user,scale
  }
}

TEST_CASE("QuestSim env: the same seed gives the same bits with 1 or 2 threads, and a new seed differs") {
  Env a(clips(), meta(), std::vector<double>(6, 1.75), 5), b(clips(), meta(), std::vector<double>(6, 1.75), 5);
  Env c(clips(), meta(), std::vector<double>(6, 1.75), 6);
  bool differs = false;
  for (int t = 0; t < 60; ++t) {
    const auto act = random_actions(6, 100 + t, 0.05f);
    a.step(act.data(), 1);
    b.step(act.data(), 2);
    c.step(act.data(), 1);
    REQUIRE(std::memcmp(a.observations(), b.observations(), sizeof(float) * 6 * Env::kObservationSize) == 0);
    REQUIRE(std::memcmp(a.rewards(), b.rewards(), sizeof(float) * 6) == 0);
    REQUIRE(std::memcmp(a.terminated(), b.terminated(), 6) == 0);
    differs = differs || std::memcmp(a.observations(), c.observations(), sizeof(float) * 6 * Env::kObservationSize) != 0;
  }
  CHECK(differs);
}

TEST_CASE("QuestSim env: rewards in [0, 1]; zero torques fall, the residual root force keeps them up") {
  auto falls = [](double residual) {
    training::QuestSimEnvConfig cfg;
    cfg.residual_max_force = residual;
    cfg.residual_max_torque = residual / 3;
    cfg.max_head_error = 10;  // only falls end an episode here
    Env env(clips(), meta(), std::vector<double>(4, 1.75), 3, cfg);
    const std::vector<float> zero(std::size_t(4) * Env::kActionSize, 0.f);
    int n = 0;
    for (int t = 0; t < 72; ++t) {
      env.step(zero.data());
      for (int i = 0; i < 4; ++i) {
        CHECK(env.rewards()[i] >= 0.f);
        CHECK(env.rewards()[i] <= 1.f);
        n += env.terminated()[i] == 2;
      }
    }
    return n;
  };
  const int without = falls(0), with = falls(600);
  MESSAGE("falls in 2 s x 4 characters: " << without << " without, " << with << " with a 600 N residual");
  CHECK(without >= 4);
  CHECK(with * 4 <= without);  // the residual holds most of them up
}

TEST_CASE("QuestSim env: non-finite actions are zero torques, never a non-finite observation") {
  Env env(clips(), meta(), std::vector<double>(2, 1.75), 1);
  std::vector<float> act(std::size_t(2) * Env::kActionSize, std::nanf(""));
  act[3] = std::numeric_limits<float>::infinity();
  for (int t = 0; t < 20; ++t) {
    env.step(act.data());
    for (int k = 0; k < 2 * Env::kObservationSize; ++k) REQUIRE(std::isfinite(env.observations()[k]));
    REQUIRE(std::isfinite(env.rewards()[0]));
  }
}

TEST_CASE("QuestSim env: the action mapping and the joints are the run-time pipeline's (torque limits, damping, armature)") {
  Env env(clips(), meta(), {1.62}, 1);
  const auto lim = control::questsim_torque_limits(env.model(0), 1.62 / 1.75);
  const auto pipe = control::questsim_torque_limits(character::avatar_for_user_height<float, 24, 72>(1.62), 1.62 / 1.75);
  CHECK((lim - pipe).cwiseAbs().maxCoeff() == 0.f);
  CHECK(lim(6) > 0.f);
  const avatar::QuestSimConfig run_time;
  CHECK(run_time.joint_armature > 0);
  for (int b = 1; b < env.model(0).nb; ++b) {
    CHECK(env.model(0).bodies[b].armature == float(run_time.joint_armature));
    CHECK(env.model(0).bodies[b].damping == float(run_time.joint_damping));
  }
}

TEST_CASE("QuestSim env: neutral starts put the character where the pipeline resets it (neutral pose at rest under the headset)") {
  training::QuestSimEnvConfig cfg;
  cfg.neutral_start = 1.0;
  Env env(clips(), meta(), std::vector<double>(4, 1.75), 3, cfg);
  for (int i = 0; i < env.size(); ++i) {
    const auto& m = env.model(i);
    auto q = m.neutral_configuration();
    control::questsim_stand_under_headset(control::cast_sensor_frame<float>(env.sensor(i)), q);
    CHECK((env.simulator(i).q() - q).cwiseAbs().maxCoeff() == 0.f);
    CHECK(env.simulator(i).v().cwiseAbs().maxCoeff() == 0.f);
    CHECK(std::hypot(double(q(0)) - env.sensor(i)[0].position.x(), double(q(2)) - env.sensor(i)[0].position.z()) < 1e-6);
  }
  // and a share of them: with 0.5 some characters start in the reference state, some neutral
  cfg.neutral_start = 0.5;
  Env mixed(clips(), meta(), std::vector<double>(16, 1.75), 4, cfg);
  int neutral = 0;
  for (int i = 0; i < mixed.size(); ++i) neutral += mixed.simulator(i).v().cwiseAbs().maxCoeff() == 0.f;
  CHECK(neutral > 0);
  CHECK(neutral < mixed.size());
}

TEST_CASE("QuestSim env: step() with one thread never allocates (resets included, with and without the expert)") {
  for (bool expert : {false, true}) {
    CAPTURE(expert);
    training::QuestSimEnvConfig cfg;
    cfg.expert = expert;
    cfg.record_reference = !expert;  // the world model's records (reference observations, frames)
    cfg.neutral_start = expert ? 0.0 : 0.5;  // both kinds of restart
    Env env(clips(), meta(), std::vector<double>(4, 1.75), 2, cfg);
    const auto act = random_actions(4, 9, 0.05f);
    for (int t = 0; t < 5; ++t) env.step(act.data());
    long long n = 0;
    int ended = 0;
    {
      sparsebody_test::AllocationCounter counter;
      for (int t = 0; t < 200; ++t) {
        env.step(act.data());
        for (int i = 0; i < 4; ++i) ended += env.terminated()[i] || env.truncated()[i];
      }
      n = counter.count();
    }
    CHECK(ended > 0);  // restarts were exercised
    CHECK(n == 0);
    CHECK((std::abs(env.expert_actions()[0]) + std::abs(env.expert_actions()[7]) > 0.f) == expert);
  }
}

TEST_CASE("QuestSim reward: 1 for a perfect match; one joint off by d gives exp(-k d^2 / joints)") {
  using Model = dynamics::Model<float, 24, 72>;
  const Model m = character::avatar_for_user_height<float, 24, 72>(1.75);
  Model::VecQ q = m.neutral_configuration();
  Model::VecV v = Model::VecV::Zero(m.nv);
  dynamics::Data<float, 24, 72> a(m), b(m);
  dynamics::forward_kinematics(m, a, q, &v);
  dynamics::forward_kinematics(m, b, q, &v);
  training::QuestSimRewardConfig cfg;
  auto r = training::questsim_reward(m, a, q, v, b, q, v, {600, 0}, {600, 0}, cfg);
  for (int k = 0; k < 5; ++k) CHECK(r.r[k] == doctest::Approx(1.0));
  CHECK(r.total == doctest::Approx(1.0));
  // Turn one ball joint (the Head's) by d about X: only r(q) changes before kinematics are redone.
  const int head = m.find("Head");
  const double d = 0.2;
  Model::VecQ q2 = q;
  const int k0 = m.bodies[head].q_index;
  q2(k0) = float(std::cos(d / 2)); q2(k0 + 1) = float(std::sin(d / 2)); q2(k0 + 2) = 0; q2(k0 + 3) = 0;
  int joints = 0;
  for (int i = 0; i < m.nb; ++i) joints += m.bodies[i].joint != dynamics::JointType::Free;
  r = training::questsim_reward(m, a, q2, v, b, q, v, {600, 0}, {600, 0}, cfg);
  CHECK(r.r[0] == doctest::Approx(std::exp(-40.0 * d * d / joints)).epsilon(1e-4));
  cfg.mean_over_joints = false;
  r = training::questsim_reward(m, a, q2, v, b, q, v, {600, 0}, {600, 0}, cfg);
  CHECK(r.r[0] == doctest::Approx(std::exp(-40.0 * d * d)).epsilon(1e-4));
  // A foot unloading by 200 N: r_f = exp(-0.01 * 200).
  r = training::questsim_reward(m, a, q, v, b, q, v, {600, 300}, {400, 300}, cfg);
  CHECK(r.r[4] == doctest::Approx(std::exp(-2.0)));
  // Loading a foot is not penalised.
  r = training::questsim_reward(m, a, q, v, b, q, v, {400, 300}, {600, 300}, cfg);
  CHECK(r.r[4] == doctest::Approx(1.0));
}

TEST_CASE("QuestSim env: the privileged expert keeps its episodes going longer than zero torques (residual on)") {
  // With the root held by a 1000 N residual, zero torques let the upper body fold until the head is
  // lost; the expert keeps it up. (Mean reward per step is no better: 0.477 against 0.480 on 40
  // training clips, where episodes last 67.9 against 13.4 control steps.)
  auto run = [](bool expert) {
    training::QuestSimEnvConfig cfg;
    cfg.residual_max_force = 1000;
    cfg.residual_max_torque = 300;
    cfg.expert = true;
    Env env(clips(), meta(), std::vector<double>(4, 1.75), 8, cfg);
    std::vector<float> act(std::size_t(4) * Env::kActionSize, 0.f);
    int ended = 0;
    for (int t = 0; t < 144; ++t) {
      if (expert) std::copy(env.expert_actions(), env.expert_actions() + act.size(), act.begin());
      for (float a : act) REQUIRE(std::abs(a) <= 1.f);
      env.step(act.data());
      for (int i = 0; i < 4; ++i) ended += env.terminated()[i] != 0;
    }
    return ended;
  };
  const int zero = run(false), expert = run(true);
  MESSAGE("terminated episodes in 4 s x 4 characters: zero torques " << zero << ", expert " << expert);
  CHECK(expert * 2 < zero);
}

TEST_CASE("QuestSim env: a restart never starts a contact point inside the floor (the reference is lifted)") {
  Env env(clips(), meta(), std::vector<double>(8, 1.75), 21);
  for (int round = 0; round < 3; ++round) {
    for (int i = 0; i < env.size(); ++i) {
      const auto& d = env.simulator(i).data();
      const auto& m = env.model(i);
      double lowest = 1e9;
      for (int p = 0; p < m.num_points; ++p) {
        const auto& cp = m.points[p];
        lowest = std::min(lowest, double((d.p[cp.body] + d.R[cp.body] * cp.pos).y() - cp.radius));
      }
      CHECK(lowest > -1e-4);
      CHECK(lowest < 0.05);
    }
    env.reset_all();
  }
}

TEST_CASE("QuestSim env: stance support moves the expert's root wrench onto the feet (checked by RNEA's root rows)") {
  // With contact limits that never bind, RNEA with the feet's wrenches as external forces must leave
  // nothing on the root (the rows the floating base cannot actuate); with the default limits, never
  // more than there was.
  for (bool generous : {true, false}) {
    CAPTURE(generous);
    training::QuestSimEnvConfig cfg;
    cfg.expert = true;
    cfg.expert_support = true;
    cfg.expert_support_height = 0.04;
    cfg.residual_max_force = 600;
    cfg.residual_max_torque = 200;
    if (generous) cfg.expert_friction = 100, cfg.expert_cop_radius = 10, cfg.expert_yaw_radius = 10;
    Env env(clips(), meta(), std::vector<double>(4, 1.75), 9, cfg);
    std::vector<float> act(std::size_t(4) * Env::kActionSize, 0.f);
    int supported = 0;
    for (int t = 0; t < 36; ++t) {
      for (int i = 0; i < 4; ++i) {
        const auto w = env.expert_root_wrench(i);
        REQUIRE(std::isfinite(w[1]));
        if (w[1] < w[0]) ++supported;
        if (generous && w[1] < w[0]) CHECK(w[1] < 1e-3 * w[0] + 1e-2);
        CHECK(w[1] <= w[0] * 1.0001 + 1e-3);
      }
      std::copy(env.expert_actions(), env.expert_actions() + act.size(), act.begin());
      env.step(act.data());
    }
    CHECK(supported > 36 * 4 / 2);  // standing on the floor most of the time: the support acts
  }
}
