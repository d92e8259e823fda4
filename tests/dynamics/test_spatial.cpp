// Spatial algebra against the dense 6x6 definitions.
#include <doctest/doctest.h>

#include <cstdio>
#include <limits>
#include <random>

#include "sparsebody/dynamics/spatial.hpp"

using namespace sparsebody::dynamics;

TEST_CASE("spatial: transforms and inertia shifts match the 6x6 matrices") {
  std::mt19937 rng(1);
  std::normal_distribution<double> n;
  for (int it = 0; it < 100; ++it) {
    Transform<double> X;
    X.E = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
    X.r = Vec3<double>(n(rng), n(rng), n(rng));
    Vec6<double> m, f;
    for (int k = 0; k < 6; ++k) { m(k) = n(rng); f(k) = n(rng); }
    const Mat6<double> Xm = X.matrix();
    CHECK((X.apply(m) - Xm * m).norm() < 1e-12);
    CHECK((X.apply_inverse(X.apply(m)) - m).norm() < 1e-12);
    CHECK((X.apply_transpose_force(f) - Xm.transpose() * f).norm() < 1e-12);
    // X^T I X with a random SPD I
    Mat6<double> A = Mat6<double>::Random();
    Mat6<double> I = A * A.transpose();
    Mat6<double> out = Mat6<double>::Zero();
    add_transformed_inertia(X, I, out);
    CHECK((out - Xm.transpose() * I * Xm).norm() < 1e-10 * I.norm());
    // the lower-triangle kernel (ABA's pass 2): reads only I's lower triangle (NaN above it here),
    // adds only to out's lower triangle (NaN above it stays NaN, nothing else does)
    Mat6<double> I_low = I, acc = Mat6<double>::Random();
    Mat6<double> acc_low = acc;
    for (int c = 0; c < 6; ++c)
      for (int r = 0; r < c; ++r) I_low(r, c) = acc_low(r, c) = std::numeric_limits<double>::quiet_NaN();
    add_transformed_inertia_lower(X, I_low, acc_low);
    const Mat6<double> want = acc + Xm.transpose() * I * Xm;
    for (int c = 0; c < 6; ++c)
      for (int r = 0; r < 6; ++r) {
        if (r >= c) CHECK(std::abs(acc_low(r, c) - want(r, c)) < 1e-10 * I.norm());
        else CHECK(std::isnan(acc_low(r, c)));
      }
    CHECK((mul6v_lower(I_low, m) - I * m).norm() < 1e-12 * I.norm() * m.norm());
    // composition
    Transform<double> Y;
    Y.E = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
    Y.r = Vec3<double>(n(rng), n(rng), n(rng));
    CHECK(((Y * X).matrix() - Y.matrix() * Xm).norm() < 1e-12);
    // cross products: (v x*) = -(v x)^T
    Vec6<double> v;
    for (int k = 0; k < 6; ++k) v(k) = n(rng);
    CHECK(std::abs(cross_force(v, f).dot(m) + f.dot(cross_motion(v, m))) < 1e-12);
  }
}

TEST_CASE("spatial: quaternion exp/log round trip") {
  for (double a : {1e-9, 1e-4, 0.3, 2.0, 3.1}) {
    Vec3<double> w = Vec3<double>(0.3, -0.5, 0.8).normalized() * a;
    CHECK((quat_log(quat_exp(w)) - w).norm() < 1e-12);
    CHECK(std::abs(quat_exp(w).norm() - 1) < 1e-15);
  }
}

#include "sparsebody/character/avatar.hpp"
#include "sparsebody/dynamics/aba.hpp"
#include "sparsebody/dynamics/jacobian.hpp"
#include "test_util.hpp"

TEST_CASE("body and point Jacobians reproduce FK velocities") {
  const auto m = sparsebody::character::default_avatar<double>();
  using Mo = std::decay_t<decltype(m)>;
  Data<double, 24, 72> d(m);
  std::mt19937 rng(21);
  Mo::VecQ q;
  Mo::VecV qd;
  double worst = 0;
  for (int t = 0; t < 50; ++t) {
    dyn_test::random_state(m, rng, q, qd);
    forward_kinematics(m, d, q, &qd);
    for (int i = 0; i < m.nb; ++i) {
      const Vec3<double> p(0.05, -0.02, 0.1);
      Eigen::Matrix<double, 6, Eigen::Dynamic> J(6, m.nv);
      body_jacobian(m, d, i, p, J);
      Eigen::Matrix<double, 6, 1> ref;
      ref.head<3>() = d.R[i] * d.v[i].head<3>();
      ref.tail<3>() = point_velocity(d, i, p);
      worst = std::max(worst, (J * qd - ref).norm() / std::max(1.0, ref.norm()));
      Eigen::Matrix<double, 3, Eigen::Dynamic> Jp(3, m.nv);
      point_jacobian(m, d, i, p, Jp);
      worst = std::max(worst, (Jp * qd - ref.tail<3>()).norm() / std::max(1.0, ref.norm()));
    }
  }
  CHECK(worst < 1e-12);
}

TEST_CASE("float ABA agrees with double ABA") {
  const auto md = sparsebody::character::default_avatar<double>();
  const auto mf = md.cast<float>();
  Data<double, 24, 72> dd(md);
  Data<float, 24, 72> df(mf);
  std::mt19937 rng(22);
  using Mo = std::decay_t<decltype(md)>;
  Mo::VecQ q;
  Mo::VecV qd, tau, qdd;
  double worst = 0;
  for (int t = 0; t < 100; ++t) {
    dyn_test::random_state(md, rng, q, qd);
    tau = Mo::VecV::Constant(md.nv, 5.0);
    dyn_test::aba_damped(md, dd, q, qd, tau, qdd, 1.0 / 120);
    decltype(mf)::VecQ qf = q.cast<float>();
    decltype(mf)::VecV qdf = qd.cast<float>(), tauf = tau.cast<float>(), qddf;
    dyn_test::aba_damped(mf, df, qf, qdf, tauf, qddf, 1.0f / 120);
    worst = std::max(worst, (qddf.cast<double>() - qdd).norm() / qdd.norm());
  }
  std::printf("[float] ABA float vs double: max rel err %.2e\n", worst);
  CHECK(worst < 1e-4);
}

// mul_rigid_inertia equals the dense I x, and its two-lane form (RNEA's I a and I v together)
// equals two one-lane calls: with the compiler's vectors (float, double) and the plain pair (long
// double).
template <class S>
void check_rigid_inertia_lanes(std::mt19937& rng) {
  std::normal_distribution<double> n;
  const Vec3<S> c(S(n(rng)), S(n(rng)), S(n(rng)));
  const Mat3<S> A = Mat3<S>::Random();
  const Mat6<S> I = rigid_inertia(S(2.5), c, Mat3<S>(A * A.transpose()));
  S x[6], y[6], u[6], z[6];
  for (int k = 0; k < 6; ++k) x[k] = S(n(rng)), y[k] = S(n(rng));
  mul_rigid_inertia(I, x, u);
  mul_rigid_inertia(I, y, z);
  const Vec6<S> dense = I * Eigen::Map<const Vec6<S>>(x);
  for (int k = 0; k < 6; ++k) CHECK(double(std::abs(u[k] - dense(k))) < 1e-5 * double(I.norm()));
  Lanes2<S> xy[6], out[6];
  for (int k = 0; k < 6; ++k) xy[k] = Lanes2Of<S>::make(x[k], y[k]);
  mul_rigid_inertia(I, xy, out);
  // the same arithmetic per lane (a compiler may contract the lanes' and the scalars' products
  // into FMAs differently: equal to rounding)
  const double tol = 80 * double(std::numeric_limits<S>::epsilon()) * double(I.norm());
  for (int k = 0; k < 6; ++k) {
    CHECK(double(std::abs(out[k][0] - u[k])) <= tol);
    CHECK(double(std::abs(out[k][1] - z[k])) <= tol);
  }
}
TEST_CASE("spatial: rigid inertia product, one lane and two") {
  std::mt19937 rng(3);
  for (int it = 0; it < 20; ++it) {
    check_rigid_inertia_lanes<double>(rng);
    check_rigid_inertia_lanes<float>(rng);
    check_rigid_inertia_lanes<long double>(rng);
  }
}
