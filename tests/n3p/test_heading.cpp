// Heading-frame algebra (features/heading_frame.hpp): composition, inverse, delta, transforms.
#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include "sparsebody/features/heading_frame.hpp"
#include "sparsebody/features/n3p_tracker_input.hpp"

using sparsebody::features::HeadingFrame;
using sparsebody::features::wrap_angle;

namespace {
HeadingFrame random_frame(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-3, 3), a(-3.14159, 3.14159);
  return {u(rng), u(rng), a(rng)};
}
bool same(const HeadingFrame& a, const HeadingFrame& b, double tol = 1e-12) {
  return std::abs(a.px - b.px) < tol && std::abs(a.pz - b.pz) < tol && std::abs(wrap_angle(a.theta - b.theta)) < tol;
}
}  // namespace

TEST_CASE("heading frame: R_y(theta) maps +Z to (sin theta, 0, cos theta); from() inverts it") {
  const HeadingFrame h{0, 0, 0.7};
  const Eigen::Vector3d z = h.rotation() * Eigen::Vector3d::UnitZ();
  CHECK(z.x() == doctest::Approx(std::sin(0.7)));
  CHECK(z.z() == doctest::Approx(std::cos(0.7)));
  CHECK(HeadingFrame::from(Eigen::Vector3d(1, 5, 2), z).theta == doctest::Approx(0.7));
  CHECK(HeadingFrame::from(Eigen::Vector3d(1, 5, 2), z).px == 1.0);
  CHECK(std::abs(h.rotation().determinant() - 1) < 1e-12);
}

TEST_CASE("one heading: heading_angle gives HeadingFrame::from's theta and yaw_frame's rotation") {
  using namespace sparsebody::features;
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0, 1);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d f(n(rng), n(rng), n(rng));
    const double t = heading_angle(f);
    CHECK(t == std::atan2(f.x(), f.z()));
    CHECK(HeadingFrame::from(Eigen::Vector3d::Zero(), f).theta == t);
    CHECK(yaw_frame(f, Eigen::Matrix3d::Zero()) == HeadingFrame{0, 0, t}.rotation());
    // the normalised ground projection (the Python twin's yaw_frame) to rounding
    const Eigen::Vector3d z = Eigen::Vector3d(f.x(), 0, f.z()).normalized();
    CHECK((yaw_frame(f, Eigen::Matrix3d::Zero()).col(2) - z).norm() < 1e-15);
    // float callers keep float arithmetic
    const Eigen::Vector3f ff = f.cast<float>();
    CHECK(heading_angle(ff, 1e-6f) == std::atan2(ff.x(), ff.z()));
  }
  CHECK(heading_angle(Eigen::Vector3d(0, 1, 0)) == 0.0);  // vertical: no heading
  CHECK(yaw_frame(Eigen::Vector3d(1e-4, 1, 0), Eigen::Matrix3d::Zero()).isZero());  // fallback
}

TEST_CASE("heading frame: group laws") {
  std::mt19937 rng(3);
  for (int i = 0; i < 200; ++i) {
    const HeadingFrame a = random_frame(rng), b = random_frame(rng), c = random_frame(rng);
    CHECK(same((a * b) * c, a * (b * c), 1e-9));                 // associativity
    CHECK(same(a * a.inverse(), HeadingFrame::identity()));       // h (x) inv(h) = id
    CHECK(same(a.inverse() * a, HeadingFrame::identity()));
    CHECK(same(a * HeadingFrame::delta(a, b), b, 1e-9));          // h_t = h_{t-1} (x) dh
    CHECK(same(HeadingFrame::delta(a, b), a.inverse() * b, 1e-9));
    CHECK(a.theta > -M_PI - 1e-12);
    CHECK((a * b).theta <= M_PI);
    // points: world -> local -> world, and composition acts like matrix products
    const Eigen::Vector3d p(0.3 * i, 1.1, -0.2 * i);
    CHECK((a.point_to_world(a.point_to_local(p)) - p).norm() < 1e-9);
    CHECK(((a * b).point_to_world(p) - a.point_to_world(b.point_to_world(p))).norm() < 1e-9);
    CHECK((a.inverse().point_to_world(p) - a.point_to_local(p)).norm() < 1e-9);
    // vectors ignore the translation; heights are untouched
    CHECK((a.vector_to_local(p) - a.rotation().transpose() * p).norm() < 1e-12);
    CHECK(a.point_to_local(p).y() == p.y());
  }
}

TEST_CASE("heading frame: theta wraps across +-pi") {
  const HeadingFrame a{0, 0, 3.0}, d{0, 0, 0.5};
  const HeadingFrame b = a * d;
  CHECK(b.theta == doctest::Approx(3.5 - 2 * M_PI));
  CHECK(HeadingFrame::delta(a, b).theta == doctest::Approx(0.5));
}

TEST_CASE("n3p tracker input: o in a heading frame and back") {
  namespace n3p = sparsebody::features::n3p;
  const HeadingFrame h{1.0, -2.0, 2.5};
  n3p::TrackerSet o;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Matrix3d R = Eigen::AngleAxisd(0.3 + k, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    o[k] = n3p::TrackerSample::from(Eigen::Vector3d(k, 1.5, -k), R);
  }
  double x[n3p::kO];
  n3p::tracker_input(h, o, x);
  // the head straight in front of a frame at its position appears on +Z
  const HeadingFrame at{0, -1.5, 0.0};
  n3p::TrackerSet o2 = o;
  o2[0].p = Eigen::Vector3d(0, 1.5, 0);
  double y[n3p::kO];
  n3p::tracker_input(at, o2, y);
  CHECK(y[0] == doctest::Approx(0.0));
  CHECK(y[2] == doctest::Approx(1.5));
  for (int k = 0; k < 3; ++k) {
    const n3p::TrackerSample s = n3p::tracker_from_local(h, x, k);
    CHECK((s.p - o[k].p).norm() < 1e-12);
    CHECK((s.fwd - o[k].fwd).norm() < 1e-12);
    CHECK((s.up - o[k].up).norm() < 1e-12);
  }
}
