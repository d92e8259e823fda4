// Neural3Points correction-policy environment (training/n3p_env.hpp) and the correction itself
// (control/n3p_target_correction.hpp) on a synthetic clip of the standard skeleton (arms swinging
// while standing, creeping forwards): the action mapping is exact (hinge angle + scale a, ball joint
// Q exp(scale a), clamped, non-finite = 0), zero actions give the model-based controller's targets
// (the reference 2 frames ahead) bit for bit, the same seed gives the same bits with 1 or 2 threads,
// the residual bound is what the characters get, and step() never allocates.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "sparsebody/character/avatar.hpp"
#include "sparsebody/predict/n3p_predictor.hpp"
#include "sparsebody/training/n3p_env.hpp"
#include "support/alloc_counter.hpp"
#include "training/synthetic_clip.hpp"

using namespace sparsebody;
using Env = training::N3PEnv;

namespace {

std::shared_ptr<const std::vector<training::QuestSimReference>> clips30() {
  static auto c = [] {
    auto v = std::make_shared<std::vector<training::QuestSimReference>>();
    v->push_back(training::make_questsim_reference(training_test::synthetic_clip(), training_test::meta().skeleton, "synthetic", 30.0));
    return v;
  }();
  return c;
}

std::vector<float> random_actions(int n, unsigned seed, float scale) {
  return training_test::random_actions<Env::kActionSize>(n, seed, scale);
}

bool same_bits(const float* a, const float* b, std::size_t n) { return std::memcmp(a, b, n * sizeof(float)) == 0; }

}  // namespace

TEST_CASE("N3P correction: hinge angle + scale a, ball joint Q exp(scale a); clamped to [-1, 1]; non-finite = 0") {
  using M = dynamics::Model<float, 24, 72>;
  const M m = character::default_avatar<float, 24, 72>();
  REQUIRE(m.nv - 6 == Env::kActionSize);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  M::VecQ q = m.neutral_configuration();
  M::VecV v = M::VecV::Zero(m.nv), zero = M::VecV::Zero(m.nv);
  for (int k = 6; k < m.nv; ++k) v(k) = 0.3f * u(rng);
  dynamics::integrate(m, q, v, zero, 1.f);  // a non-trivial reference configuration
  std::vector<float> a(static_cast<std::size_t>(Env::kActionSize));
  for (auto& x : a) x = 1.5f * u(rng);
  a[0] = std::numeric_limits<float>::quiet_NaN();
  a[5] = std::numeric_limits<float>::infinity();
  const double scale = 0.2;
  M::VecV delta = M::VecV::Zero(m.nv);
  M::VecQ out = q;
  control::n3p_correction::apply(m, a.data(), scale, delta, out);
  CHECK(out.head<7>() == q.head<7>());  // the root is not a servo target here
  int hinges = 0, balls = 0;
  for (int b = 0; b < m.nb; ++b) {
    const auto& body = m.bodies[b];
    const int j = body.v_index - 6;
    auto expect = [&](int k) {
      const float x = a[j + k];
      return std::isfinite(x) ? float(scale) * std::fmin(1.f, std::fmax(-1.f, x)) : 0.f;
    };
    if (body.joint == dynamics::JointType::Revolute) {
      ++hinges;
      CHECK(out(body.q_index) == doctest::Approx(q(body.q_index) + expect(0)).epsilon(1e-6));
    } else if (body.joint == dynamics::JointType::Spherical) {
      ++balls;
      const Eigen::Quaternionf Q0 = dynamics::read_quat<float>(q, body.q_index), Q1 = dynamics::read_quat<float>(out, body.q_index);
      const Eigen::Quaternionf D = Q0.conjugate() * Q1;  // exp(delta), body frame
      const Eigen::AngleAxisf aa(D);
      const Eigen::Vector3f d(expect(0), expect(1), expect(2));
      CHECK((aa.angle() * aa.axis() - d).norm() < 2e-5f);
    }
  }
  CHECK(hinges > 0);
  CHECK(balls > 0);
}

TEST_CASE("N3P env: zero actions set the model-based controller's targets (the reference 2 frames ahead), bit for bit") {
  training::N3PEnvConfig cfg;
  Env env(clips30(), training_test::meta(), 4, 7, cfg);
  std::vector<float> zero(static_cast<std::size_t>(env.size()) * Env::kActionSize, 0.f);
  int checked = 0;
  for (int t = 0; t < 40; ++t) {
    env.step(zero.data());
    for (int i = 0; i < env.size(); ++i) {
      if (env.episode_step(i) == 0) continue;  // restarted in this step
      const auto& u = env.targets(i);
      const auto& r = env.reference_q(i, 2);
      // the free root comes first (7 entries); the controller writes its own root target there
      CHECK(u.segment(7, u.size() - 7) == r.segment(7, r.size() - 7));
      ++checked;
    }
  }
  CHECK(checked > 100);
}

TEST_CASE("N3P env: the same seed gives the same bits with 1 or 2 threads, a new seed differs; non-finite actions are zero") {
  training::N3PEnvConfig cfg;
  cfg.max_episode_steps = 25;  // restarts inside the run
  Env a(clips30(), training_test::meta(), 6, 11, cfg), b(clips30(), training_test::meta(), 6, 11, cfg),
      c(clips30(), training_test::meta(), 6, 12, cfg);
  const std::size_t no = std::size_t(a.size()) * Env::kObservationSize;
  REQUIRE(same_bits(a.observations(), b.observations(), no));
  for (int t = 0; t < 60; ++t) {
    const auto act = random_actions(a.size(), 100 + t, 0.5f);
    a.step(act.data(), 1);
    b.step(act.data(), 2);
    c.step(act.data(), 1);
    REQUIRE(same_bits(a.observations(), b.observations(), no));
    REQUIRE(same_bits(a.rewards(), b.rewards(), std::size_t(a.size())));
  }
  CHECK_FALSE(same_bits(a.observations(), c.observations(), no));
  for (std::size_t k = 0; k < no; ++k) REQUIRE(std::isfinite(a.observations()[k]));

  Env z(clips30(), training_test::meta(), 3, 5, cfg), n(clips30(), training_test::meta(), 3, 5, cfg);
  std::vector<float> zero(std::size_t(z.size()) * Env::kActionSize, 0.f), bad = zero;
  for (std::size_t k = 0; k < bad.size(); ++k) bad[k] = k % 2 ? std::numeric_limits<float>::quiet_NaN() : -std::numeric_limits<float>::infinity() * 0.f;
  for (int t = 0; t < 30; ++t) {
    z.step(zero.data());
    n.step(bad.data());
    REQUIRE(same_bits(z.observations(), n.observations(), std::size_t(z.size()) * Env::kObservationSize));
  }
}

TEST_CASE("N3P env: the residual bound is what the characters get; rewards in [0, 1 + residual_weight]") {
  training::N3PEnvConfig cfg;
  Env env(clips30(), training_test::meta(), 4, 3, cfg);
  std::vector<float> zero(std::size_t(env.size()) * Env::kActionSize, 0.f);
  double used = 0;
  for (int t = 0; t < 30; ++t) {
    env.step(zero.data());
    for (int i = 0; i < env.size(); ++i) {
      used += env.residual_force(i);
      CHECK(env.rewards()[i] >= 0.f);
      CHECK(env.rewards()[i] <= 1.f + float(cfg.residual_weight) + 1e-6f);
      CHECK(env.residual_force(i) <= cfg.controller.max_force + 1e-3);
    }
  }
  CHECK(used > 0);  // the default bound (620 N) helps
  env.set_residual(0, 0);
  for (int t = 0; t < 30; ++t) {
    env.step(zero.data());
    for (int i = 0; i < env.size(); ++i) CHECK(env.residual_force(i) == 0.0);
  }
}

TEST_CASE("N3P env: step() with one thread never allocates (restarts included)") {
  training::N3PEnvConfig cfg;
  cfg.max_episode_steps = 7;
  Env env(clips30(), training_test::meta(), 4, 9, cfg);
  const auto act = random_actions(env.size(), 1, 2.0f);  // large: falls and clamps too
  env.step(act.data());
  sparsebody_test::AllocationCounter counter;
  for (int t = 0; t < 50; ++t) env.step(act.data());
  CHECK(counter.count() == 0);
}
