// Spatial algebra against the dense 6x6 definitions.
#include <doctest/doctest.h>

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
    CHECK((X.applyInverse(X.apply(m)) - m).norm() < 1e-12);
    CHECK((X.applyTransposeForce(f) - Xm.transpose() * f).norm() < 1e-12);
    // X^T I X with a random SPD I
    Mat6<double> A = Mat6<double>::Random();
    Mat6<double> I = A * A.transpose();
    Mat6<double> out = Mat6<double>::Zero();
    addTransformedInertia(X, I, out);
    CHECK((out - Xm.transpose() * I * Xm).norm() < 1e-10 * I.norm());
    // composition
    Transform<double> Y;
    Y.E = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
    Y.r = Vec3<double>(n(rng), n(rng), n(rng));
    CHECK(((Y * X).matrix() - Y.matrix() * Xm).norm() < 1e-12);
    // cross products: (v x*) = -(v x)^T
    Vec6<double> v;
    for (int k = 0; k < 6; ++k) v(k) = n(rng);
    CHECK(std::abs(crossForce(v, f).dot(m) + f.dot(crossMotion(v, m))) < 1e-12);
  }
}

TEST_CASE("spatial: quaternion exp/log round trip") {
  for (double a : {1e-9, 1e-4, 0.3, 2.0, 3.1}) {
    Vec3<double> w = Vec3<double>(0.3, -0.5, 0.8).normalized() * a;
    CHECK((quatLog(quatExp(w)) - w).norm() < 1e-12);
    CHECK(std::abs(quatExp(w).norm() - 1) < 1e-15);
  }
}
