// ABA (with implicit damping) against an independent solve: CRBA mass matrix + Cholesky of
// (M + h Kd) with the RNEA bias C(q, qd) (gravity included).
#include <doctest/doctest.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <cstdio>
#include <string>
#include <vector>

#include "sparsebody/character/avatar.hpp"
#include "sparsebody/character/humanoid3d.hpp"
#include "sparsebody/dynamics/aba.hpp"
#include "sparsebody/dynamics/crba.hpp"
#include "sparsebody/dynamics/rnea.hpp"
#include "test_util.hpp"

using namespace sparsebody;
using namespace sparsebody::dynamics;

// root_damping: implicit root servo damping K_r (diagonal), added to the root block of M + h Kd.
template <class Model>
static double aba_vs_crba(const Model& m, int trials, double h, unsigned seed, const Vec6<double>* root_damping = nullptr) {
  Data<double, Model::kMaxBodies, Model::kMaxDofs> d(m);
  CrbaData<double, Model::kMaxBodies, Model::kMaxDofs> crba_out(m);
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  typename Model::VecQ q;
  typename Model::VecV qd, tau, qdd, zero = Model::VecV::Zero(m.nv), C;
  double worst = 0;
  for (int t = 0; t < trials; ++t) {
    dyn_test::random_state(m, rng, q, qd);
    tau.resize(m.nv);
    for (int k = 0; k < m.nv; ++k) tau(k) = 20 * n(rng);
    REQUIRE(dyn_test::aba_damped(m, d, q, qd, tau, qdd, h, root_damping));
    rnea(m, d, q, qd, zero, C);  // C(q, qd)
    crba(m, d, q, crba_out);
    Eigen::MatrixXd M = crba_out.M;
    for (int i = 0; i < m.nb; ++i) {
      const auto& b = m.bodies[i];
      for (int k = 0; k < joint_nv(b.joint); ++k) M(b.v_index + k, b.v_index + k) += h * (b.kd + b.damping);
      if (i == m.root_body() && root_damping)
        for (int k = 0; k < 6; ++k) M(b.v_index + k, b.v_index + k) += h * (*root_damping)(k);
    }
    const Eigen::VectorXd ref = M.llt().solve(Eigen::VectorXd(tau - C));
    worst = std::max(worst, (qdd - ref).norm() / ref.norm());
    // RNEA inverts ABA without damping
    if (h == 0) {
      typename Model::VecV tau2;
      rnea(m, d, q, qd, qdd, tau2);
      worst = std::max(worst, (tau2 - tau).norm() / tau.norm());
    }
  }
  return worst;
}

TEST_CASE("ABA == (M + h Kd)^-1 (tau - C) on the 34-DoF humanoid3d-like tree") {
  const auto m = character::humanoid3d_like<double>();
  CHECK(m.nv == 34);
  const double e0 = aba_vs_crba(m, 1000, 0.0, 7);
  const double e1 = aba_vs_crba(m, 1000, 1.0 / 120, 8);
  std::printf("[aba-oracle] humanoid34: max rel err h=0 %.2e, h=1/120 %.2e\n", e0, e1);
  CHECK(e0 <= 1e-10);
  CHECK(e1 <= 1e-10);
}

TEST_CASE("ABA == (M + h Kd)^-1 (tau - C) on the default avatar") {
  const auto m = character::default_avatar<double>();
  const double e0 = aba_vs_crba(m, 1000, 0.0, 9);
  const double e1 = aba_vs_crba(m, 1000, 1.0 / 120, 10);
  std::printf("[aba-oracle] avatar (%d DoF): max rel err h=0 %.2e, h=1/120 %.2e\n", m.nv, e0, e1);
  CHECK(e0 <= 1e-10);
  CHECK(e1 <= 1e-10);
}

TEST_CASE("ABA with implicit root servo damping == (M + h (Kd + K_r))^-1 (tau - C) on the default avatar") {
  const auto m = character::default_avatar<double>();
  Vec6<double> kr;
  kr << 50, 60, 70, 300, 400, 500;  // N m s/rad on the angular, N s/m on the linear DoFs
  const double e = aba_vs_crba(m, 1000, 1.0 / 120, 11, &kr);
  const double e_plain = aba_vs_crba(m, 1, 1.0 / 120, 11);
  // The oracle must see the root damping: without it in ABA the same states disagree.
  Data<double, 24, 72> d(m);
  std::mt19937 rng(11);
  std::decay_t<decltype(m)>::VecQ q;
  std::decay_t<decltype(m)>::VecV qd, tau = std::decay_t<decltype(m)>::VecV::Constant(m.nv, 5.0), a, b;
  dyn_test::random_state(m, rng, q, qd);
  dyn_test::aba_damped(m, d, q, qd, tau, a, 1.0 / 120);
  dyn_test::aba_damped(m, d, q, qd, tau, b, 1.0 / 120, &kr);
  std::printf("[aba-oracle] avatar with root damping: max rel err %.2e (without: %.2e); root qdd changed by %.2e\n", e, e_plain,
              (a - b).head<6>().norm());
  CHECK(e <= 1e-10);
  CHECK((a - b).head<6>().norm() > 1e-3);
}

// Armature (Body::armature, rotor inertia on each joint DoF's diagonal): ABA, CRBA and RNEA all
// include it, so the same oracle holds, and it must change the answer (light segments turn slower).
TEST_CASE("ABA == (M + diag(armature) + h Kd)^-1 (tau - C) on the default avatar with armature") {
  auto m = character::default_avatar<double>();
  const auto plain = m;
  for (int i = 1; i < m.nb; ++i) m.bodies[i].armature = 0.01 + 0.01 * (i % 7);
  m.finalize();
  const double e0 = aba_vs_crba(m, 1000, 0.0, 13);  // also RNEA(ABA(tau)) == tau
  const double e1 = aba_vs_crba(m, 1000, 1.0 / 120, 14);
  Data<double, 24, 72> d(m), dp(plain);
  std::mt19937 rng(15);
  std::decay_t<decltype(m)>::VecQ q;
  std::decay_t<decltype(m)>::VecV qd, tau = std::decay_t<decltype(m)>::VecV::Constant(m.nv, 5.0), a, b;
  dyn_test::random_state(m, rng, q, qd);
  REQUIRE(dyn_test::aba_damped(m, d, q, qd, tau, a, 0.0));
  REQUIRE(dyn_test::aba_damped(plain, dp, q, qd, tau, b, 0.0));
  std::printf("[aba-oracle] avatar with armature: max rel err h=0 %.2e, h=1/120 %.2e; qdd changed by %.2e (rel)\n", e0, e1,
              (a - b).norm() / b.norm());
  CHECK(e0 <= 1e-10);
  CHECK(e1 <= 1e-10);
  CHECK((a - b).norm() > 0.05 * b.norm());
}

// ---- pass 2 in pairs (Model::backward_steps) ------------------------------------------------------

// Every body stepped once, each after all its children, and a pair's two bodies with the same
// spherical or revolute joint, both with parents.
template <class Model>
static int check_backward_plan(const Model& m) {
  REQUIRE(m.backward_steps_nb == m.nb);
  std::vector<int> step_of(m.nb, -1);
  int pairs = 0;
  for (int s = 0; s < m.num_backward_steps; ++s) {
    const auto& st = m.backward_steps[s];
    for (const int k : st) {
      if (k < 0) continue;
      REQUIRE(k < m.nb);
      CHECK(step_of[k] == -1);
      step_of[k] = s;
    }
    if (st[1] >= 0) {
      ++pairs;
      const auto &a = m.bodies[st[0]], &b = m.bodies[st[1]];
      CHECK(a.joint == b.joint);
      CHECK((a.joint == JointType::Spherical || a.joint == JointType::Revolute));
      CHECK(a.parent >= 0);
      CHECK(b.parent >= 0);
    }
  }
  for (int i = 0; i < m.nb; ++i) {
    REQUIRE(step_of[i] >= 0);
    if (m.bodies[i].parent >= 0) CHECK(step_of[i] < step_of[m.bodies[i].parent]);  // children first
  }
  return pairs;
}

// qdd from the paired plan against the plain reverse order (and the unplanned fallback), with
// implicit damping, armature and external loads f_ext, K_ext (a contact solve's): equal to rounding.
template <class S, class Model>
static double paired_vs_plain(const Model& model, int trials, unsigned seed) {
  const auto m = model.template cast<S>();
  auto plain = m, unplanned = m;
  plain.plan_backward_steps(false);
  unplanned.backward_steps_nb = -1;
  CHECK(check_backward_plan(plain) == 0);
  constexpr int MB = Model::kMaxBodies, MD = Model::kMaxDofs;
  Data<S, MB, MD> d(m), dp(plain), du(unplanned);
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  typename Model::VecQ q;
  typename Model::VecV qd;
  double worst = 0;
  for (int t = 0; t < trials; ++t) {
    dyn_test::random_state(model, rng, q, qd);
    const auto qs = q.template cast<S>().eval();
    const auto qds = qd.template cast<S>().eval();
    typename dynamics::Model<S, MB, MD>::VecV tau(m.nv), a, b, c;
    for (int k = 0; k < m.nv; ++k) tau(k) = S(20 * n(rng));
    for (auto* x : {&d, &dp, &du}) {
      implicit_damping_diagonal(m, S(1.0 / 120), true, x->implicit_diagonal);
      x->clear_external();
    }
    if (t % 2) {  // contact-like loads on a few bodies: a force and an added SPD inertia
      for (int i = 0; i < m.nb; i += 3) {
        Vec6<S> f;
        Mat6<S> A;
        for (int r = 0; r < 6; ++r) f(r) = S(30 * n(rng));
        for (int r = 0; r < 36; ++r) A.data()[r] = S(n(rng));
        const Mat6<S> K = S(5) * A * A.transpose();
        for (auto* x : {&d, &dp, &du}) {
          x->fext[i] = f;
          x->Kext[i] = K;
          x->has_ext = true;
        }
      }
    }
    REQUIRE(aba(m, d, qs, qds, tau, a));
    REQUIRE(aba(plain, dp, qs, qds, tau, b));
    REQUIRE(aba(unplanned, du, qs, qds, tau, c));
    worst = std::max({worst, double((a - b).norm() / b.norm()), double((c - b).norm() / b.norm())});
  }
  return worst;
}

// A random tree (parents before children) of free root, spherical, revolute and fixed joints.
static Model<double, 24, 72> random_tree(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.2, 1.0);
  Model<double, 24, 72> m;
  const auto body = [&](int parent, JointType jt) {
    Body<double> b;
    b.parent = parent;
    b.joint = jt;
    b.pos = Vec3<double>(u(rng) - 0.6, u(rng) - 0.6, u(rng) - 0.6);
    b.rot = Quat<double>(u(rng), u(rng) - 0.6, u(rng) - 0.6, u(rng) - 0.6).normalized();
    b.axis = Vec3<double>(u(rng) - 0.6, u(rng) - 0.6, u(rng) - 0.6);
    b.mass = 3 * u(rng);
    b.com = Vec3<double>(u(rng) - 0.6, u(rng) - 0.6, u(rng) - 0.6) * 0.3;
    b.inertia = Vec3<double>(u(rng), u(rng), u(rng)).asDiagonal() * 0.05;
    b.kd = jt == JointType::Free ? 0.0 : 10 * u(rng);  // (the free root's damping is the root servo's)
    b.armature = 0.01 * u(rng);
    return b;
  };
  m.add_body("root", body(-1, JointType::Free));
  const int n = 6 + int(rng() % 14);
  for (int i = 1; i < n; ++i) {
    const JointType jt = std::array<JointType, 4>{JointType::Spherical, JointType::Revolute, JointType::Spherical,
                                                  JointType::Fixed}[rng() % 4];
    REQUIRE(m.add_body("b" + std::to_string(i), body(int(rng() % i), jt)) == i);
  }
  return m;
}

TEST_CASE("ABA pass 2 pairs the humanoid's mirrored limbs and equals the plain order to rounding") {
  const auto m = character::humanoid3d_like<double>();
  CHECK(check_backward_plan(m) == 5);  // hips, knees, ankles, shoulders, elbows
  for (int s = 0; s < m.num_backward_steps; ++s) {
    const auto& st = m.backward_steps[s];
    if (st[1] < 0) continue;
    std::string a = m.names[st[0]], b = m.names[st[1]];
    CHECK(a.substr(a.find('_')) == b.substr(b.find('_')));  // left_knee with right_knee
  }
  const auto avatar = character::default_avatar<double>();
  const int avatar_pairs = check_backward_plan(avatar);
  CHECK(avatar_pairs >= 8);
  const double hd = paired_vs_plain<double>(m, 200, 21), hf = paired_vs_plain<float>(m, 200, 22);
  const double ad = paired_vs_plain<double>(avatar, 200, 23), af = paired_vs_plain<float>(avatar, 200, 24);
  std::printf("[aba-pairs] avatar: %d pairs of %d bodies; paired vs plain qdd, max rel: humanoid34 double %.1e float %.1e, "
              "avatar double %.1e float %.1e\n",
              avatar_pairs, avatar.nb, hd, hf, ad, af);
  CHECK(hd <= 1e-12);
  CHECK(ad <= 1e-12);
  CHECK(hf <= 1e-4);
  CHECK(af <= 1e-4);
}

TEST_CASE("ABA pass 2 plans any tree: every body once, children first, paired equals plain") {
  std::mt19937 rng(31);
  int pairs = 0;
  double worst = 0;
  for (int t = 0; t < 40; ++t) {
    const auto m = random_tree(rng);
    pairs += check_backward_plan(m);
    const double e_pair = paired_vs_plain<double>(m, 5, 100 + t);
    const double e_oracle = aba_vs_crba(m, 5, 1.0 / 120, 200 + t);  // and against the CRBA oracle
    worst = std::max({worst, e_pair, e_oracle});
  }
  std::printf("[aba-pairs] 40 random trees (7-19 bodies): %d pairs; paired vs plain and vs CRBA, max rel err %.1e\n", pairs, worst);
  CHECK(pairs > 40);
  CHECK(worst <= 1e-9);
}
