// ABA (with implicit damping) against an independent solve: CRBA mass matrix + Cholesky of
// (M + h Kd) with the RNEA bias C(q, qd) (gravity included).
#include <doctest/doctest.h>

#include <Eigen/Cholesky>
#include <cstdio>

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
