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

template <class Model>
static double abaVsCrba(const Model& m, int trials, double h, unsigned seed) {
  Data<double, Model::kMaxBodies, Model::kMaxDofs> d(m);
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  typename Model::VecQ q;
  typename Model::VecV qd, tau, qdd, zero = Model::VecV::Zero(m.nv), C;
  double worst = 0;
  for (int t = 0; t < trials; ++t) {
    dyn_test::randomState(m, rng, q, qd);
    tau.resize(m.nv);
    for (int k = 0; k < m.nv; ++k) tau(k) = 20 * n(rng);
    REQUIRE(aba(m, d, q, qd, tau, qdd, h));
    rnea(m, d, q, qd, zero, C);  // C(q, qd)
    crba(m, d, q);
    Eigen::MatrixXd M = d.Mass;
    for (int i = 0; i < m.nb; ++i) {
      const auto& b = m.bodies[i];
      for (int k = 0; k < jointNv(b.joint); ++k) M(b.v_index + k, b.v_index + k) += h * (b.kd + b.damping);
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
  const auto m = character::humanoid3dLike<double>();
  CHECK(m.nv == 34);
  const double e0 = abaVsCrba(m, 1000, 0.0, 7);
  const double e1 = abaVsCrba(m, 1000, 1.0 / 120, 8);
  std::printf("[aba-oracle] humanoid34: max rel err h=0 %.2e, h=1/120 %.2e\n", e0, e1);
  CHECK(e0 <= 1e-10);
  CHECK(e1 <= 1e-10);
}

TEST_CASE("ABA == (M + h Kd)^-1 (tau - C) on the default avatar") {
  const auto m = character::defaultAvatar<double>();
  const double e0 = abaVsCrba(m, 1000, 0.0, 9);
  const double e1 = abaVsCrba(m, 1000, 1.0 / 120, 10);
  std::printf("[aba-oracle] avatar (%d DoF): max rel err h=0 %.2e, h=1/120 %.2e\n", m.nv, e0, e1);
  CHECK(e0 <= 1e-10);
  CHECK(e1 <= 1e-10);
}
