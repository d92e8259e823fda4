// Contact post-processing (paper §3.4.1) and the IK pieces it uses.
#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include "sparsebody/pose/contact.hpp"
#include "sparsebody/pose/foot_roll.hpp"
#include "sparsebody/pose/ik.hpp"
#include "sparsebody/trackers/stillness.hpp"

using namespace sparsebody;
using Eigen::Vector3d;

TEST_CASE("foot lock: lock at contact, hold, 10-frame slow-in-slow-out release") {
  pose::FootLock lock(10);
  const Vector3d hip(0, 0.9, 0);
  Vector3d target;
  CHECK_FALSE(lock.update(false, Vector3d(0.1, 0.1, 0.2), hip, 1.0, 0.1, 0.042, target));
  REQUIRE(lock.update(true, Vector3d(0.1, 0.06, 0.2), hip, 1.0, 0.1, 0.042, target));
  CHECK(target.isApprox(Vector3d(0.1, 0.042, 0.2)));  // at the standing toe height
  REQUIRE(lock.update(true, Vector3d(0.15, 0.05, 0.22), hip, 1.0, 0.1, 0.042, target));  // network toe drifts 5 cm
  CHECK(target.isApprox(Vector3d(0.1, 0.042, 0.2)));  // held
  // release: the target goes from the lock to the network's toe with w_k = (1 - cos(pi k / 10)) / 2
  const Vector3d toe(0.3, 0.1, 0.2);
  double prev = -1;
  for (int k = 1; k <= 10; ++k) {
    REQUIRE(lock.update(false, toe, hip, 1.0, 0.1, 0.042, target));
    const double w = (target.x() - 0.1) / (0.3 - 0.1);
    CHECK(w == doctest::Approx(0.5 - 0.5 * std::cos(M_PI * k / 10)));
    CHECK(w > prev);
    prev = w;
  }
  CHECK(target.isApprox(toe));
  CHECK_FALSE(lock.update(false, toe, hip, 1.0, 0.1, 0.042, target));  // free again
}

TEST_CASE("foot lock: released when the network's toe leaves it or the leg cannot reach; no re-lock until contact goes off") {
  pose::FootLock lock(10);
  Vector3d target;
  const Vector3d hip(0, 0.9, 0);
  lock.update(true, Vector3d(0, 0.05, 0), hip, 1.0, 0.1, 0.042, target);
  CHECK(lock.state() == pose::FootLock::State::Locked);
  lock.update(true, Vector3d(0.2, 0.05, 0), hip, 1.0, 0.1, 0.042, target);  // 20 cm away: drift
  CHECK(lock.state() == pose::FootLock::State::Blending);
  for (int k = 0; k < 12; ++k) lock.update(true, Vector3d(0.2, 0.05, 0), hip, 1.0, 0.1, 0.042, target);
  CHECK(lock.state() == pose::FootLock::State::Free);  // contact still on, but held off
  lock.update(false, Vector3d(0.2, 0.05, 0), hip, 1.0, 0.1, 0.042, target);
  lock.update(true, Vector3d(0.2, 0.05, 0), hip, 1.0, 0.1, 0.042, target);
  CHECK(lock.state() == pose::FootLock::State::Locked);
  lock.update(true, Vector3d(0.2, 0.05, 0), Vector3d(1.5, 0.9, 0), 1.0, 0.1, 0.042, target);  // hip walked away
  CHECK(lock.state() == pose::FootLock::State::Blending);
}

TEST_CASE("foot lock, replant (LoBSTr): a foot released while its contact stays on locks again after the blend") {
  const Vector3d hip(0, 0.9, 0);
  for (bool replant : {false, true}) {
    pose::FootLock lock(10);
    lock.set_replant(replant);
    Vector3d target;
    lock.update(true, Vector3d(0, 0.05, 0), hip, 1.0, 0.1, 0.042, target);
    lock.update(true, Vector3d(0.2, 0.05, 0), hip, 1.0, 0.1, 0.042, target);  // 20 cm away: drift
    CHECK(lock.state() == pose::FootLock::State::Blending);
    for (int k = 2; k < 10; ++k) {  // the blend runs its 10 frames either way
      REQUIRE(lock.update(true, Vector3d(0.2, 0.05, 0), hip, 1.0, 0.1, 0.042, target));
      CHECK(lock.state() == pose::FootLock::State::Blending);
    }
    REQUIRE(lock.update(true, Vector3d(0.2, 0.05, 0), hip, 1.0, 0.1, 0.042, target));  // the blend's last frame
    CHECK(lock.state() == pose::FootLock::State::Free);
    CHECK(target.isApprox(Vector3d(0.2, 0.05, 0)));
    const bool held = lock.update(true, Vector3d(0.21, 0.05, 0), hip, 1.0, 0.1, 0.042, target);
    CHECK(held == replant);
    if (replant) {  // planted where the network has it, at the standing toe height
      CHECK(lock.state() == pose::FootLock::State::Locked);
      CHECK(target.isApprox(Vector3d(0.21, 0.042, 0)));
      lock.reset();  // reset keeps the option
      lock.update(true, Vector3d(0, 0.05, 0), hip, 1.0, 0.1, 0.042, target);
      lock.update(true, Vector3d(0, 0.05, 0), Vector3d(1.5, 0.9, 0), 1.0, 0.1, 0.042, target);  // hip gone: reach
      for (int k = 0; k < 10; ++k) lock.update(true, Vector3d(0, 0.05, 0), Vector3d(1.5, 0.9, 0), 1.0, 0.1, 0.042, target);
      CHECK(lock.state() == pose::FootLock::State::Free);  // a joint out of reach is not replanted
      lock.update(true, Vector3d(1.4, 0.05, 0), Vector3d(1.5, 0.9, 0), 1.0, 0.1, 0.042, target);
      CHECK(lock.state() == pose::FootLock::State::Locked);  // the network's foot in reach again
    } else {
      CHECK(lock.state() == pose::FootLock::State::Free);
    }
  }
}

TEST_CASE("two-bone IK keeps bone lengths, reaches reachable targets, bends towards the pole") {
  const Vector3d a(0, 1, 0), b(0, 0.55, 0.02), c(0, 0.1, 0);
  const double l1 = (b - a).norm(), l2 = (c - b).norm();
  Vector3d b2, c2;
  pose::two_bone(a, b, c, Vector3d(0.1, 0.3, 0.2), Vector3d(0, 0, 1), b2, c2);
  CHECK((b2 - a).norm() == doctest::Approx(l1));
  CHECK((c2 - b2).norm() == doctest::Approx(l2));
  CHECK((c2 - Vector3d(0.1, 0.3, 0.2)).norm() < 1e-9);
  CHECK(b2.z() > 0.2);  // knee forward, towards the pole
  pose::two_bone(a, b, c, Vector3d(0, -2, 0), Vector3d(0, 0, 1), b2, c2);  // out of reach: straight
  CHECK((c2 - a).norm() == doctest::Approx(l1 + l2).epsilon(1e-5));
  CHECK(c2.x() == doctest::Approx(0).epsilon(1e-9));
}

TEST_CASE("aim maps the primary axis exactly and the secondary as close as possible") {
  const Eigen::Quaterniond q = pose::aim(Vector3d::UnitX(), Vector3d::UnitY(), Vector3d(0, 1, 0), Vector3d(0, 0, 1));
  CHECK((q * Vector3d::UnitX() - Vector3d(0, 1, 0)).norm() < 1e-12);
  CHECK((q * Vector3d::UnitY() - Vector3d(0, 0, 1)).norm() < 1e-12);
  const Eigen::Quaterniond r = pose::aim(Vector3d::UnitX(), Vector3d::UnitY(), Vector3d(1, 0, 0), Vector3d(1, 0, 0));  // degenerate
  CHECK(r.coeffs().allFinite());
}

TEST_CASE("limb_to: the end on the target, bones carried by their swings; the rotation rules agree") {
  const Vector3d a(0, 1, 0), b(0.02, 0.55, 0.05), c(0, 0.1, 0), target(0.15, 0.35, 0.25);
  const Eigen::Quaterniond Wa(Eigen::AngleAxisd(0.4, Vector3d(1, 2, 0).normalized()));
  const Eigen::Quaterniond Wb(Eigen::AngleAxisd(-0.7, Vector3d(0, 1, 3).normalized()));
  const auto comp = pose::limb_to(a, b, c, Wa, Wb, target, b - a);
  const auto seq = pose::limb_to(a, b, c, Wa, Wb, target, b - a, pose::LimbRotation::sequential());
  CHECK((comp.c - target).norm() < 1e-9);
  CHECK(comp.b == seq.b);
  CHECK(comp.c == seq.c);
  // each bone's direction in its joint's frame is unchanged: W' W^-1 maps the old bone onto the new
  CHECK(((comp.upper * Wa.conjugate()) * (b - a) - (comp.b - a)).norm() < 1e-9);
  CHECK(((comp.lower * Wb.conjugate()) * (c - b) - (comp.c - comp.b)).norm() < 1e-9);
  CHECK(comp.upper.angularDistance(seq.upper) < 1e-12);
  CHECK(comp.lower.angularDistance(seq.lower) < 1e-12);
  // the same solve on rotation matrices (the control predictor's 6D rotations)
  const auto mat = pose::limb_to(a, b, c, Eigen::Matrix3d(Wa.toRotationMatrix()), Eigen::Matrix3d(Wb.toRotationMatrix()), target, b - a);
  CHECK((mat.upper - comp.upper.toRotationMatrix()).norm() < 1e-12);
  CHECK((mat.lower - comp.lower.toRotationMatrix()).norm() < 1e-12);
  // aimed bones: each bone axis along its new direction, the side axis towards the twist
  const auto aimed = pose::limb_to(a, b, c, Wa, Wb, target, Vector3d(0, 0, 1),
                                   pose::LimbRotation::aimed(Vector3d::UnitX(), Vector3d::UnitX(), Vector3d::UnitY(), Vector3d::UnitZ()));
  CHECK((aimed.upper * Vector3d::UnitX() - (aimed.b - a).normalized()).norm() < 1e-12);
  CHECK((aimed.lower * Vector3d::UnitX() - (aimed.c - aimed.b).normalized()).norm() < 1e-12);
  // locals: L_a = W_p^-1 W_a', L_b = W_a'^-1 W_b', L_c = W_b'^-1 W_c
  pose::BodyPose p;
  p.resize(4);
  const int j[3] = {1, 2, 3};
  const Eigen::Quaterniond Wp(Eigen::AngleAxisd(0.2, Vector3d::UnitY())), Wc(Eigen::AngleAxisd(1.0, Vector3d::UnitX()));
  pose::set_limb_locals(p, j, &Wp, comp.upper, comp.lower, Wc, true);
  CHECK((Wp * p.local[1]).angularDistance(comp.upper) < 1e-12);
  CHECK((Wp * p.local[1] * p.local[2]).angularDistance(comp.lower) < 1e-12);
  CHECK((Wp * p.local[1] * p.local[2] * p.local[3]).angularDistance(Wc) < 1e-12);
}

TEST_CASE("foot lock, direct-mode options: pinned at the joint's own height; Rearm orders the hold-off") {
  Vector3d target;
  const Vector3d hip(0, 0.9, 0);
  pose::FootLock pin(8, pose::FootLock::Rearm::NextFrame);
  REQUIRE(pin.update(true, Vector3d(0.1, 0.08, 0.2), hip, 1.0, 0.1, target));
  CHECK(target == Vector3d(0.1, 0.08, 0.2));  // no height given: where the ankle is
  for (int k = 1; k <= 8; ++k) REQUIRE(pin.update(false, Vector3d(0.3, 0.08, 0.2), hip, 1.0, 0.1, target));
  CHECK(pin.state() == pose::FootLock::State::Free);  // 8-frame release
  // A lock released for drift on a frame whose contact is already off: with SameFrame (LoBSTr)
  // that off frame re-arms it, so the next contact locks again; with NextFrame (direct mode) the
  // hold-off lasts until a later off frame.
  for (auto rearm : {pose::FootLock::Rearm::SameFrame, pose::FootLock::Rearm::NextFrame}) {
    pose::FootLock lock(8, rearm);
    lock.update(true, Vector3d(0, 0.05, 0), hip, 1.0, 0.1, target);
    lock.update(false, Vector3d(0.5, 0.05, 0), hip, 1.0, 0.1, target);  // off and 50 cm away
    CHECK(lock.state() == pose::FootLock::State::Blending);
    lock.update(true, Vector3d(0.5, 0.05, 0), hip, 1.0, 0.1, target);
    CHECK(lock.state() == (rearm == pose::FootLock::Rearm::SameFrame ? pose::FootLock::State::Locked
                                                                     : pose::FootLock::State::Blending));
  }
}

TEST_CASE("foot lock hold: while the user stands still a lock survives contact off and drift, slides back into reach, not a hip gone away") {
  pose::FootLock lock(10);
  const Vector3d hip(0, 0.9, 0);
  Vector3d target;
  REQUIRE(lock.update(true, Vector3d(0.1, 0.05, 0.2), hip, 1.0, 0.1, 0.042, target));
  lock.hold(true);
  // the network flickers the contact off and lets the toe creep 30 cm: the lock holds
  for (int k = 0; k < 20; ++k) {
    REQUIRE(lock.update(k % 2 == 0, Vector3d(0.1 + 0.015 * k, 0.05, 0.2), hip, 1.0, 0.1, 0.042, target));
    CHECK(target.isApprox(Vector3d(0.1, 0.042, 0.2)));
  }
  CHECK(lock.state() == pose::FootLock::State::Locked);
  // a hip that moves away with the lock at full stretch: the lock (put at 0.042, caught at 0.05)
  // first rises back towards 0.05, then slides after the hip on the floor, just back into reach,
  // and stays locked (it was released to the network's toe)
  const Vector3d lock0 = target;
  const double reach = (lock0 - hip).norm();
  const Vector3d away = Vector3d(0.1, 0, 0.2).normalized();
  const Vector3d hip2 = hip - 0.002 * away;  // a little: rising is enough
  REQUIRE(lock.update(true, Vector3d(0.5, 0.05, 0.2), hip2, reach, 0.1, 0.042, target));
  CHECK(lock.state() == pose::FootLock::State::Locked);
  CHECK((target - hip2).norm() == doctest::Approx(reach));
  CHECK(target.y() > 0.042 + 1e-4);
  CHECK(target.y() < 0.05);
  CHECK(target.x() == doctest::Approx(0.1));
  CHECK(target.z() == doctest::Approx(0.2));
  // 5 cm (the near-vertical leg gets 2.5 cm of horizontal reach back from the 8 mm rise): it rises
  // to 0.05 and slides the other ~2 cm
  const Vector3d hip3 = hip - 0.05 * away;
  REQUIRE(lock.update(true, Vector3d(0.5, 0.05, 0.2), hip3, reach, 0.1, 0.042, target));
  CHECK(lock.state() == pose::FootLock::State::Locked);
  CHECK((target - hip3).norm() <= reach);
  CHECK((target - hip3).norm() == doctest::Approx(reach));
  CHECK(target.y() == doctest::Approx(0.05));
  CHECK((target - lock0).norm() < 0.03);
  CHECK((target - lock0).norm() > 0.015);
  // a hip that walked away: the reach limit still releases it (blend towards the network's toe)
  REQUIRE(lock.update(true, Vector3d(1.6, 0.05, 0.2), Vector3d(1.5, 0.9, 0), 1.0, 0.1, 0.042, target));
  CHECK(lock.state() == pose::FootLock::State::Blending);
  // moving again: hold off, the normal rules apply (contact off releases)
  lock.hold(false);
  pose::FootLock l2(10);
  REQUIRE(l2.update(true, Vector3d(0.1, 0.05, 0.2), hip, 1.0, 0.1, 0.042, target));
  REQUIRE(l2.update(false, Vector3d(0.1, 0.05, 0.2), hip, 1.0, 0.1, 0.042, target));
  CHECK(l2.state() == pose::FootLock::State::Blending);
}

TEST_CASE("foot lock hold: a held-off foot the network keeps still locks again, one it moves stays free; no snap") {
  const Vector3d hip(0, 0.9, 0);
  Vector3d target;
  // walking: locked, then released by drift (the network's toe 20 cm away): held off, contact on
  auto walked_off = [&](pose::FootLock& l) {
    l.update(true, Vector3d(0, 0.05, 0), hip, 1.0, 0.1, 0.042, target);
    l.update(true, Vector3d(0.2, 0.09, 0), hip, 1.0, 0.1, 0.042, target);
    for (int k = 0; k < 12; ++k) l.update(true, Vector3d(0.2, 0.09, 0), hip, 1.0, 0.1, 0.042, target);
    REQUIRE(l.state() == pose::FootLock::State::Free);
  };
  pose::FootLock a(10);
  walked_off(a);
  a.hold(true);  // the user stands; the network creeps the toe 2 mm a frame (under 4 mm: the default)
  REQUIRE(a.update(true, Vector3d(0.202, 0.09, 0), hip, 1.0, 0.1, 0.042, target));
  CHECK(a.state() == pose::FootLock::State::Locked);
  // locked where it was shown the frame before (0.2), then eased down to the toe height
  CHECK(target.x() == doctest::Approx(0.2));
  CHECK(target.y() < 0.09);
  CHECK(target.y() > 0.042);
  double prev = target.y();
  for (int k = 2; k <= 10; ++k) {
    REQUIRE(a.update(true, Vector3d(0.2 + 0.002 * k, 0.09, 0), hip, 1.0, 0.1, 0.042, target));
    CHECK(target.x() == doctest::Approx(0.2));
    CHECK(target.y() <= prev);
    CHECK(target.y() == doctest::Approx(0.09 + (0.042 - 0.09) * (0.5 - 0.5 * std::cos(M_PI * k / 10))));
    prev = target.y();
  }
  CHECK(target.isApprox(Vector3d(0.2, 0.042, 0)));
  REQUIRE(a.update(true, Vector3d(0.3, 0.09, 0), hip, 1.0, 0.1, 0.042, target));
  CHECK(target.isApprox(Vector3d(0.2, 0.042, 0)));  // and held
  // the same foot stepping while the head stays (the network moves it 2 cm a frame): stays free
  pose::FootLock b(10);
  walked_off(b);
  b.hold(true);
  for (int k = 1; k <= 10; ++k) CHECK_FALSE(b.update(true, Vector3d(0.2 + 0.02 * k, 0.09, 0), hip, 1.0, 0.1, 0.042, target));
  // a looser rearm speed locks it
  pose::FootLock c(10);
  c.set_hold_rearm_step(0.05);
  walked_off(c);
  c.hold(true);
  CHECK(c.update(true, Vector3d(0.22, 0.09, 0), hip, 1.0, 0.1, 0.042, target));
  CHECK(c.state() == pose::FootLock::State::Locked);
  // without hold the old rule stands: held off until the contact goes off once
  pose::FootLock d(10);
  walked_off(d);
  CHECK_FALSE(d.update(true, Vector3d(0.2, 0.09, 0), hip, 1.0, 0.1, 0.042, target));
  // a lock made while moving does not settle (at the toe height at once, as before)
  pose::FootLock e(10);
  REQUIRE(e.update(true, Vector3d(0.1, 0.09, 0.2), hip, 1.0, 0.1, 0.042, target));
  CHECK(target.isApprox(Vector3d(0.1, 0.042, 0.2)));
}

TEST_CASE("stillness: a calibration's rebase keeps the state; assume_still unless the headset moves") {
  const double dt = 1.0 / 30;
  const Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  trackers::Stillness s;
  for (int i = 0; i < 30; ++i) s.update(Vector3d(0, 1.6, 0), q, dt);
  REQUIRE(s.still());
  s.rebase();  // the calibrated headset jumps 10 cm with the new offsets: no speed spike, still
  s.update(Vector3d(0.1, 1.6, 0), q, dt);
  s.update(Vector3d(0.1, 1.6, 0), q, dt);
  CHECK(s.still());
  CHECK(s.speed() < 0.01);
  trackers::Stillness t;  // 4 frames calm: not still yet, but the calibrator says the user stands
  for (int i = 0; i < 4; ++i) t.update(Vector3d(0, 1.6, 0), q, dt);
  REQUIRE_FALSE(t.still());
  t.assume_still();
  CHECK(t.still());
  for (int i = 0; i < 30; ++i) t.update(Vector3d(1.0 * i * dt, 1.6, 0), q, dt);  // walks off: released
  CHECK_FALSE(t.still());
  t.assume_still();  // walking: refused
  CHECK_FALSE(t.still());
}

TEST_CASE("stillness: still after 0.3 s of a calm headset, not while walking or turning on the spot, NaN resets") {
  trackers::Stillness s;
  const double dt = 1.0 / 30;
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  int first_still = -1;
  for (int i = 0; i < 30; ++i) {  // standing with 1 cm/s sway
    s.update(Vector3d(0.01 * std::sin(i * dt), 1.6, 0), q, dt);
    if (s.still() && first_still < 0) first_still = i;
  }
  CHECK(first_still >= 9);
  CHECK(first_still <= 16);  // 0.3 s plus the low-pass settling
  for (int i = 0; i < 30; ++i) s.update(Vector3d(1.0 * i * dt, 1.6, 0), q, dt);  // walking at 1 m/s
  CHECK_FALSE(s.still());
  trackers::Stillness t;
  for (int i = 0; i < 60; ++i)  // turning on the spot at 90 deg/s
    t.update(Vector3d(0, 1.6, 0), Eigen::Quaterniond(Eigen::AngleAxisd(i * dt * M_PI / 2, Vector3d::UnitY())), dt);
  CHECK_FALSE(t.still());
  trackers::Stillness u;
  for (int i = 0; i < 30; ++i) u.update(Vector3d(0, 1.6, 0), q, dt);
  CHECK(u.still());
  u.update(Vector3d(NAN, 1.6, 0), q, dt);
  CHECK_FALSE(u.still());
  CHECK(std::isfinite(u.speed()));
}

// The stop test (issue 12, csv stands): a walker who stops dead is still after stop_seconds, once
// (stopped_now on that frame only); not at a stream's start (the slow entry handles a user who
// stands from the first frame), not while creeping forward or turning after the stop; off with
// stop_seconds = 0 (the low-pass alone then takes ~0.9 s).
TEST_CASE("stillness: a dead stop is still after 0.1 s; not a creep, a turn or a stream's start") {
  const double dt = 1.0 / 30;
  const Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  auto frames_to_still = [&](trackers::StillnessConfig c, double creep, double turn_rate, int* stops) {
    trackers::Stillness s(c);
    double x = 0;
    for (int i = 0; i < 60; ++i) s.update(Vector3d(x += 1.3 * dt, 1.6, 0), q, dt);  // walking 1.3 m/s
    REQUIRE_FALSE(s.still());
    *stops = 0;
    for (int i = 0; i < 60; ++i) {
      const Eigen::Quaterniond r(Eigen::AngleAxisd(i * dt * turn_rate, Vector3d::UnitY()));
      s.update(Vector3d(x += creep * dt, 1.6, 0), r, dt);
      *stops += s.stopped_now();
      if (s.still()) return i;
    }
    return -1;
  };
  int stops = 0;
  const int quick = frames_to_still({}, 0.0, 0.0, &stops);
  CHECK(quick == 2);  // 0.1 s at 30 Hz: the 3 past frames (the last walking one is where it stopped) within 1 cm
  CHECK(stops == 1);
  trackers::StillnessConfig off;
  off.stop_seconds = 0;
  const int slow = frames_to_still(off, 0.0, 0.0, &stops);
  CHECK(slow > 20);  // the low-pass from 1.3 m/s to 0.06 m/s, then 0.3 s
  CHECK(stops == 0);
  MESSAGE("still after a dead stop: " << quick << " frames with the stop test, " << slow << " without");
  trackers::StillnessConfig bad;  // a NaN radius or angle: the stop test never fires
  bad.stop_radius = NAN;
  CHECK(frames_to_still(bad, 0.0, 0.0, &stops) > 20);
  CHECK(stops == 0);
  bad = {};
  bad.stop_yaw = NAN;
  CHECK(frames_to_still(bad, 0.0, 0.0, &stops) > 20);
  CHECK(stops == 0);
  CHECK(frames_to_still({}, 0.15, 0.0, &stops) == -1);  // creeping on at 15 cm/s (1.5 cm per 0.1 s): moving
  CHECK(frames_to_still({}, 0.0, 0.5, &stops) == -1);  // turning at 29 deg/s: not still at all
  {  // a real stop: 1.3 m/s down to 0 over 0.5 s, then standing; still within 0.2 s of standing
    trackers::Stillness d;
    double x = 0;
    for (int i = 0; i < 60; ++i) d.update(Vector3d(x += 1.3 * dt, 1.6, 0), q, dt);
    for (int i = 1; i <= 15; ++i) d.update(Vector3d(x += 1.3 * (1.0 - i / 15.0) * dt, 1.6, 0), q, dt);
    int standing = -1;
    for (int i = 0; i < 30 && standing < 0; ++i) {
      d.update(Vector3d(x, 1.6, 0), q, dt);
      if (d.still()) standing = i;
    }
    CHECK(standing >= 0);
    CHECK(standing <= 6);
    MESSAGE("still " << standing << " frames after a 0.5 s deceleration ends");
  }
  {  // a new calibration's scale between the stop and the test firing: the history is rescaled too
    trackers::Stillness r;
    double x = 0;
    for (int i = 0; i < 60; ++i) r.update(Vector3d(x += 1.3 * dt, 1.6, 0), q, dt);
    r.rescale(1.1);
    int frames = -1;
    for (int i = 0; i < 10 && frames < 0; ++i) {
      r.update(Vector3d(1.1 * x, 1.6, 0), q, dt);
      if (r.still()) frames = i;
    }
    CHECK(frames == 2);  // as without a rescale (an old-scale history, 26 cm away, delays it a frame)
  }
  trackers::Stillness t;  // standing from the first frame: the slow entry, no stop event
  int first = -1, events = 0;
  for (int i = 0; i < 30; ++i) {
    t.update(Vector3d(0, 1.6, 0), q, dt);
    events += t.stopped_now();
    if (t.still() && first < 0) first = i;
  }
  CHECK(events == 0);
  CHECK(first >= 9);
}

// lock_in_place: the foot locks where it was last shown (x, z scaled with the ground by k) and
// eases down to the lock height; under the hold it stays whatever the network does next; a foot
// never shown just resets.
TEST_CASE("foot lock: lock_in_place holds the shown foot, scaled with the ground, easing down") {
  const Vector3d hip(0, 0.9, 0);
  Vector3d target;
  pose::FootLock a(10);
  CHECK_FALSE(a.update(false, Vector3d(0.2, 0.09, 0.3), hip, 1.0, 0.1, 0.042, target));  // free, in the air
  const double h = 0.042;
  a.hold(true);  // as the pipelines do: the frame's hold first, then the lock (which keeps it)
  a.lock_in_place(1.1, &h);
  CHECK(a.state() == pose::FootLock::State::Locked);
  double y_prev = 0.09;
  for (int i = 0; i < 12; ++i) {  // the network swings the foot 30 cm away: ignored under the hold
    REQUIRE(a.update(false, Vector3d(0.2, 0.09, 0.3 - 0.03 * i), hip, 1.0, 0.1, 0.042, target));
    CHECK(target.x() == doctest::Approx(0.22));
    CHECK(target.z() == doctest::Approx(0.33));
    CHECK(target.y() <= y_prev + 1e-12);
    y_prev = target.y();
  }
  CHECK(target.y() == doctest::Approx(0.042));
  pose::FootLock b(10);  // never shown: nothing to hold
  b.lock_in_place(1.0, &h);
  CHECK(b.state() == pose::FootLock::State::Free);
}

// The held foot's orientation (FootLock::orient / show / stop): while the user stands still a
// locked foot keeps the orientation it was planted with, eased in over the blend when the lock is
// older than the stillness, at once when the foot locks while still or at a stop; free: untouched.
TEST_CASE("foot lock: a held foot keeps its planted orientation while still") {
  const Vector3d hip(0, 0.9, 0), toe(0.1, 0.04, 0.2);
  const Eigen::Quaterniond flat = Eigen::Quaterniond::Identity();
  auto pitch = [](double a) { return Eigen::Quaterniond(Eigen::AngleAxisd(a, Vector3d::UnitX())); };
  Vector3d target;
  // locked while walking (flat), then the user stands and the network rolls the foot 0.5 rad:
  // the foot turns back to flat over the 10-frame blend, monotonically
  pose::FootLock a(10);
  REQUIRE(a.update(true, toe, hip, 1.0, 0.1, 0.042, target));
  Eigen::Quaterniond q = flat;
  a.orient(q, false);
  CHECK(q.angularDistance(flat) < 1e-12);
  a.show(q);
  double prev = 0.5;
  for (int i = 1; i <= 12; ++i) {
    a.hold(true);
    REQUIRE(a.update(true, toe, hip, 1.0, 0.1, 0.042, target));
    q = pitch(0.5);
    a.orient(q, true);
    const double d = q.angularDistance(flat);
    CHECK(d <= prev + 1e-12);
    if (i < 10) CHECK(d > 1e-6);  // eased, not snapped
    prev = d;
    a.show(q);
  }
  CHECK(prev < 1e-9);
  // moving again: eased back out to the network's orientation
  for (int i = 0; i < 10; ++i) {
    a.hold(false);
    a.update(true, toe, hip, 1.0, 0.1, 0.042, target);
    q = pitch(0.5);
    a.orient(q, false);
  }
  CHECK(q.angularDistance(pitch(0.5)) < 1e-9);

  // a foot that locks while still keeps the orientation it locked with from that frame on
  pose::FootLock b(10);
  b.hold(true);
  REQUIRE_FALSE(b.update(false, toe, hip, 1.0, 0.1, 0.042, target));
  b.show(pitch(0.1));
  b.hold(true);
  REQUIRE(b.update(true, toe, hip, 1.0, 0.1, 0.042, target));
  q = pitch(0.2);
  b.orient(q, true);
  CHECK(q.angularDistance(pitch(0.2)) < 1e-12);
  b.show(q);
  b.hold(true);
  b.update(true, toe, hip, 1.0, 0.1, 0.042, target);
  q = pitch(0.6);  // the network rolls it: kept at the lock's 0.2 at once
  b.orient(q, true);
  CHECK(q.angularDistance(pitch(0.2)) < 1e-9);

  // a stop: a free foot locks where it was shown with the shown orientation at once; a foot never
  // shown is not locked and not turned
  pose::FootLock c(10);
  REQUIRE_FALSE(c.update(false, toe, hip, 1.0, 0.1, 0.042, target));
  c.show(pitch(0.3));
  c.hold(true);
  const double h = 0.042;
  c.stop(&h);
  CHECK(c.state() == pose::FootLock::State::Locked);
  REQUIRE(c.update(false, toe + Vector3d(0, 0, 0.2), hip, 1.0, 0.1, 0.042, target));
  CHECK(target.z() == doctest::Approx(toe.z()));
  q = flat;
  c.orient(q, true);
  CHECK(q.angularDistance(pitch(0.3)) < 1e-9);
  pose::FootLock d(10);
  d.hold(true);
  d.stop(&h);
  CHECK(d.state() == pose::FootLock::State::Free);
  CHECK_FALSE(d.update(false, toe, hip, 1.0, 0.1, 0.042, target));
}

// An own-height lock (direct mode's ankle) made at a stop puts a foot caught in the air down to the
// height of its last walking contact, as far as the leg reaches (it rises no higher than it was
// caught); x and z stay where it was shown.
TEST_CASE("foot lock: a foot caught in the air by a stop is put down to its walking contact height, within reach") {
  Vector3d target;
  const Vector3d hip(0, 0.9, 0);
  auto walk_then_swing = [&](pose::FootLock& l) {
    REQUIRE(l.update(true, Vector3d(0.1, 0.08, 0.1), hip, 1.0, 0.3, target));  // walking contact: ankle at 0.08
    for (int i = 0; i < 12; ++i) l.update(false, Vector3d(0.1, 0.08 + 0.01 * i, 0.1 + 0.02 * i), hip, 1.0, 0.3, target);
    REQUIRE(l.state() == pose::FootLock::State::Free);  // swinging, shown at y 0.19, z 0.32
  };
  pose::FootLock a(8, pose::FootLock::Rearm::NextFrame);
  walk_then_swing(a);
  a.hold(true);
  a.stop();
  double y_prev = 1;
  for (int i = 0; i < 10; ++i) {
    a.hold(true);
    REQUIRE(a.update(false, Vector3d(0.5, 0.3, 0.5), hip, 1.0, 0.3, target));
    CHECK(target.y() <= y_prev + 1e-12);
    CHECK(target.z() == doctest::Approx(0.32));
    y_prev = target.y();
  }
  CHECK(target.y() == doctest::Approx(0.08));
  // the hip higher: the leg (reach 0.98 m) cannot reach 0.08 m under (0.1, 0.32): the lock comes
  // down only to the reach sphere, x and z kept
  pose::FootLock b(8, pose::FootLock::Rearm::NextFrame);
  walk_then_swing(b);
  b.hold(true);
  b.stop();
  const Vector3d high_hip(0, 1.05, 0);
  const double reach = 0.98;
  for (int i = 0; i < 10; ++i) {
    b.hold(true);
    REQUIRE(b.update(false, Vector3d(0.5, 0.3, 0.5), high_hip, reach, 0.3, target));
    CHECK((target - high_hip).norm() <= reach + 1e-9);
  }
  CHECK(b.state() == pose::FootLock::State::Locked);
  CHECK(target.x() == doctest::Approx(0.1));
  CHECK(target.z() == doctest::Approx(0.32));
  CHECK(target.y() > 0.08 + 1e-3);
  CHECK(target.y() < 0.19);
  CHECK((target - high_hip).norm() == doctest::Approx(reach));
  // a foot never in walking contact keeps its own height
  pose::FootLock c(8, pose::FootLock::Rearm::NextFrame);
  c.update(false, Vector3d(0.1, 0.19, 0.1), hip, 1.0, 0.3, target);
  c.hold(true);
  c.stop();
  for (int i = 0; i < 10; ++i) {
    c.hold(true);
    c.update(false, Vector3d(0.5, 0.3, 0.5), hip, 1.0, 0.3, target);
  }
  CHECK(target.y() == doctest::Approx(0.19));
}

TEST_CASE("foot roll: a toe-pinned foot turns about its toe by the least angle that puts the ankle in reach") {
  // A foot whose toe offset is 12 cm forward and 6 cm down in its frame; the foot frame yawed.
  const Vector3d t(0, -0.06, 0.12);
  const Vector3d toe(0.3, 0.04, -0.1);
  const double reach = 0.8;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  int rolled = 0, unreachable = 0, in_reach = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const Eigen::Quaterniond foot(Eigen::AngleAxisd(3 * u(rng), Vector3d::UnitY()) * Eigen::AngleAxisd(0.5 * u(rng), Vector3d::UnitX()));
    const Vector3d hip = toe + Vector3d(0.4 * u(rng), 0.75 + 0.1 * u(rng), 0.4 * u(rng));
    const double max_roll = 1.0;
    // the ankle's elevation above the toe, measured towards the unrolled foot's heel (beyond 90 deg:
    // the foot turned over)
    const Vector3d back = Vector3d(-(foot * t).x(), 0, -(foot * t).z()).normalized();
    auto elevation_of = [&](const Vector3d& ankle) { return std::atan2((ankle - toe).y(), (ankle - toe).dot(back)); };
    const Eigen::Quaterniond r = pose::roll_foot_into_reach(foot, toe, t, hip, reach, max_roll);
    REQUIRE(r.coeffs().allFinite());
    const Vector3d ankle0 = toe - foot * t, ankle = toe - r * t;
    const double angle = r.angularDistance(foot);
    if ((hip - ankle0).norm() <= 0.999 * reach) {  // in reach already: unchanged
      CHECK(r.coeffs() == foot.coeffs());
      ++in_reach;
      continue;
    }
    if ((hip - ankle).norm() > 0.999 * reach + 1e-9) {
      // still out of reach: no roll within max_roll and the elevation bounds reaches, and the one
      // taken brings the ankle nearest the hip (unchanged when none brings it nearer)
      const Vector3d lat = (foot * t).cross(Vector3d::UnitY()).normalized();
      for (double a = -max_roll; a <= max_roll; a += 0.01) {  // within the elevation bounds
        const Vector3d ankle_a = toe - Eigen::AngleAxisd(a, lat) * (foot * t);
        const double elevation = elevation_of(ankle_a);
        if (elevation < -1e-9 || elevation > 80 * M_PI / 180 + 1e-9) continue;
        CHECK((hip - ankle_a).norm() > 0.999 * reach - 1e-9);
        CHECK((hip - ankle_a).norm() >= (hip - ankle).norm() - 1e-9);
      }
      CHECK((hip - ankle).norm() <= (hip - ankle0).norm() + 1e-12);
      CHECK(angle <= max_roll + 1e-12);
      const double elevation = elevation_of(ankle);
      if (angle > 0) {
        CHECK((r * t).cross(Vector3d::UnitY()).normalized().isApprox(lat, 1e-9));  // about the lateral axis
        CHECK(elevation >= -1e-9);
        CHECK(elevation <= 80 * M_PI / 180 + 1e-9);
      }
      ++unreachable;
      continue;
    }
    ++rolled;
    CHECK((hip - ankle).norm() == doctest::Approx(0.999 * reach).epsilon(1e-9));  // just in reach
    CHECK(angle <= max_roll + 1e-12);
    // about the foot's lateral axis: that axis is unchanged, so the foot keeps its heading
    const Vector3d lat0 = (foot * t).cross(Vector3d::UnitY()).normalized(), lat = (r * t).cross(Vector3d::UnitY()).normalized();
    CHECK((lat - lat0).norm() < 1e-9);
    // the least angle: half of it is still out of reach
    const Eigen::Quaterniond half = foot.slerp(0.5, r);
    CHECK((hip - (toe - half * t)).norm() > 0.999 * reach);
    // the ankle between the toe's height and 80 deg above it
    const double elevation = elevation_of(ankle);
    CHECK(elevation >= -1e-9);
    CHECK(elevation <= 80 * M_PI / 180 + 1e-9);
  }
  MESSAGE(rolled << " rolled, " << unreachable << " unreachable, " << in_reach << " in reach");
  CHECK(rolled > 50);
  CHECK(unreachable > 10);
  CHECK(in_reach > 10);
  // a hip right above a pinned flat foot, just beyond the leg's reach: the heel rises; behind the
  // foot: the heel comes down (never below the toe)
  const Eigen::Quaterniond flat = Eigen::Quaterniond::Identity();
  const Vector3d ankle_flat = toe - flat * t;  // 6 cm above the toe, 12 cm behind it
  const Eigen::Quaterniond up = pose::roll_foot_into_reach(flat, toe, t, ankle_flat + Vector3d(0, reach + 0.03, 0), reach, 1.0);
  CHECK((toe - up * t).y() > ankle_flat.y() + 0.01);
  const Eigen::Quaterniond down = pose::roll_foot_into_reach(flat, toe, t, ankle_flat + Vector3d(0, 0.05, -0.80), reach, 1.0);
  CHECK((toe - down * t).y() < ankle_flat.y() - 1e-3);  // (the least turn: 6 mm here)
  CHECK((toe - down * t).y() >= toe.y() - 1e-12);
  const Eigen::Quaterniond heel_up(Eigen::AngleAxisd(-0.6, Vector3d::UnitX()));
  // degenerate input: NaN hip or a zero-length foot leaves the foot as it is
  CHECK(pose::roll_foot_into_reach(heel_up, toe, t, Vector3d::Constant(NAN), reach, 1.0).coeffs() == heel_up.coeffs());
  CHECK(pose::roll_foot_into_reach(heel_up, toe, Vector3d::Zero(), toe + Vector3d(0, 1, 0), reach, 1.0).coeffs() == heel_up.coeffs());
}

TEST_CASE("foot roll: lower_heel brings a raised heel down towards the standing elevation, at most max_turn a call") {
  const Vector3d t(0, -0.06, 0.12);  // toe 12 cm forward and 6 cm down in the foot frame
  auto elevation = [&](const Eigen::Quaterniond& f) {
    const Vector3d e = -(f * t);
    return std::asin(e.y() / e.norm());
  };
  const double standing = elevation(Eigen::Quaterniond::Identity());  // ~26.6 deg
  const Eigen::Quaterniond yaw(Eigen::AngleAxisd(0.7, Vector3d::UnitY()));
  const Eigen::Quaterniond heel_up = yaw * Eigen::Quaterniond(Eigen::AngleAxisd(0.6, Vector3d::UnitX()));  // 0.6 rad up
  REQUIRE(elevation(heel_up) == doctest::Approx(standing + 0.6));
  const Eigen::Quaterniond step = pose::lower_heel(heel_up, t, standing, 0.1);
  CHECK(elevation(step) == doctest::Approx(standing + 0.5));
  // about the lateral axis: the heading is kept
  const Vector3d lat0 = (heel_up * t).cross(Vector3d::UnitY()).normalized(), lat = (step * t).cross(Vector3d::UnitY()).normalized();
  CHECK((lat - lat0).norm() < 1e-9);
  // down to the standing elevation and no further
  Eigen::Quaterniond f = heel_up;
  for (int i = 0; i < 20; ++i) f = pose::lower_heel(f, t, standing, 0.1);
  CHECK(elevation(f) == doctest::Approx(standing).epsilon(1e-9));
  CHECK(f.angularDistance(yaw) < 1e-9);
  // a foot at or below the standing elevation, or a degenerate one, is left as it is
  const Eigen::Quaterniond toe_up = yaw * Eigen::Quaterniond(Eigen::AngleAxisd(-0.2, Vector3d::UnitX()));
  CHECK(pose::lower_heel(toe_up, t, standing, 0.1).coeffs() == toe_up.coeffs());
  CHECK(pose::lower_heel(heel_up, Vector3d::Zero(), standing, 0.1).coeffs() == heel_up.coeffs());
  CHECK(pose::lower_heel(heel_up, t, standing, 0.0).coeffs() == heel_up.coeffs());
}
