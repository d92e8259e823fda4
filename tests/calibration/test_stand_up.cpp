// The user sits down for 5 s and stands up again (trackers/stand_up.hpp): the detector alone (a
// rest low then a rise is one stand-up; a bow, a jump from a stand, stairs, NaN are none), and
// LoBSTr and Neural3Points with the shipped weights on the device session of the CMU clip 01_01
// (72 Hz) with a seated break at its start: 1 s down (the headset 0.42 m lower and 0.1 m ahead,
// the belt 0.47 m lower, the controllers on the lap), 5 s seated, 1.5 s up, 5 s standing still,
// then the session. One stand-up (none in the session without the break: its stand, walk and
// jumps), no non-finite output, no allocation through the restart. What the restart is worth is
// measured on validation sessions (offdist's seated mode, README).
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "sparsebody/avatar/lobstr_pipeline.hpp"
#include "sparsebody/avatar/n3p_direct.hpp"
#include "sparsebody/avatar/n3p_physics.hpp"
#include "sparsebody/trackers/stand_up.hpp"
#define SPARSEBODY_ALLOC_COUNTER_USE_ONLY  // test_recenter.cpp defines the operators
#include "support/alloc_counter.hpp"
#include "support/device_session.hpp"

using namespace sparsebody;

namespace {

constexpr double kAt = 0.0;                               // s: the break starts here
constexpr double kDown = 1.0, kSeated = 5.0, kUp = 1.5;   // s
constexpr double kBreak = kDown + kSeated + kUp;
constexpr double kStand = 5.0;                            // s standing still after it

// The session with (seated) the seated break and then kStand s standing at kAt, or the stand alone;
// later frames shifted. `inserted`: how many frames were added.
std::vector<trackers::TrackerFrame> with_break(const std::vector<trackers::TrackerFrame>& s, bool seated, std::size_t& inserted) {
  std::size_t cut = 0;
  while (cut + 1 < s.size() && s[cut + 1].time <= kAt) ++cut;
  const trackers::TrackerFrame& at = s[cut];
  const double dt = s[1].time - s[0].time;
  const Eigen::Quaterniond qh = trackers::to_eigen(at.pose[0].orientation);
  Eigen::Vector3d fwd = qh * Eigen::Vector3d(0, 0, -1);
  fwd.y() = 0;
  fwd.normalize();
  const Eigen::Vector3d drop[4] = {0.10 * fwd - Eigen::Vector3d(0, 0.42, 0), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                                   -Eigen::Vector3d(0, 0.47, 0)};
  std::vector<trackers::TrackerFrame> out(s.begin(), s.begin() + static_cast<long>(cut) + 1);
  const int n_break = seated ? static_cast<int>(kBreak / dt) : 0, n = n_break + static_cast<int>(kStand / dt);
  for (int i = 1; i <= n; ++i) {
    const double t = i * dt;
    if (i > n_break) {  // standing still as at kAt
      trackers::TrackerFrame f = at;
      f.time = at.time + t;
      out.push_back(f);
      continue;
    }
    double a = t < kDown ? t / kDown : t < kDown + kSeated ? 1.0 : std::max(0.0, 1 - (t - kDown - kSeated) / kUp);
    a = a * a * (3 - 2 * a);  // 0 standing, 1 seated
    trackers::TrackerFrame f = at;
    f.time = at.time + t;
    for (int k = 0; k < 4; ++k) {
      Eigen::Vector3d p = trackers::to_eigen(at.pose[k].position);
      if (k == 1 || k == 2) {  // the hands on the lap: 0.3 m ahead of where they were, at 0.62 m
        Eigen::Vector3d lap = p + 0.3 * fwd;
        lap.y() = 0.62;
        p = (1 - a) * p + a * lap;
      } else {
        p += a * drop[k] + Eigen::Vector3d(0.004 * a * std::sin(2 * M_PI * 0.3 * t), 0, 0);  // seated sway
      }
      f.pose[k].position = trackers::to_xr(p);
    }
    out.push_back(f);
  }
  inserted = static_cast<std::size_t>(n);
  for (std::size_t i = cut + 1; i < s.size(); ++i) {
    out.push_back(s[i]);
    out.back().time += n * dt;
  }
  return out;
}

// The stand-ups found, non-finite frames and allocations while the session with the seated
// break ran; the same for the session without it.
struct Result {
  long long stand_ups = 0, stand_ups_plain = 0;
  int nonfinite = 0;
  long long allocations = 0;
  bool output = false;
};

template <class P, class W, class Cfg>
Result run(const W& w, const Cfg& cfg) {
  std::size_t stand_only = 0, inserted = 0;
  const auto plain = with_break(sparsebody_test::device_session_01_01(), false, stand_only);
  const auto broken = with_break(sparsebody_test::device_session_01_01(), true, inserted);
  P a(w, cfg), b(w, cfg);
  for (const auto& f : plain) a.push(f);
  Result r;
  b.push(broken[0]);
  {
    sparsebody_test::AllocationCounter c;
    for (std::size_t i = 1; i < broken.size(); ++i) {
      b.push(broken[i]);
      if (!b.has_output()) continue;
      for (const auto& p : b.world().position) r.nonfinite += !p.allFinite();
    }
    r.allocations = c.count();
  }
  r.output = b.has_output();
  r.stand_ups = b.stand_ups();
  r.stand_ups_plain = a.stand_ups();
  return r;
}

template <class P, class W, class Cfg>
void check_stand_up(const W& w, Cfg cfg) {
  const Result on = run<P>(w, cfg);
  CHECK(on.stand_ups == 1);        // the seated break's
  CHECK(on.stand_ups_plain == 0);  // the session's own stand, walk and jumps are none
  CHECK(on.nonfinite == 0);
  CHECK(on.allocations == 0);
  CHECK(on.output);
  cfg.stand_up.enabled = false;
  CHECK(run<P>(w, cfg).stand_ups == 0);
}

}  // namespace

TEST_CASE("stand-up detector: 2 s resting low then 0.4 s up is one stand-up; a bow, a jump, stairs or NaN are none") {
  const double dt = 1.0 / 30;
  using V = Eigen::Vector3d;
  // `seconds` at a fixed headset position (still or not), or moving linearly from `from` to `to`
  auto hold = [&](trackers::StandUp& s, const V& p, bool still, double seconds) {
    int n = 0;
    for (int i = 0; i < static_cast<int>(std::lround(seconds / dt)); ++i) n += s.update(p, still, dt);
    return n;
  };
  auto move = [&](trackers::StandUp& s, const V& from, const V& to, bool still, double seconds) {
    int n = 0;
    const int k = static_cast<int>(std::lround(seconds / dt));
    for (int i = 1; i <= k; ++i) n += s.update(from + (to - from) * (double(i) / k), still, dt);
    return n;
  };
  const V stand(0.3, 1.60, -0.2), seat(0.3, 1.18, -0.4);
  trackers::StandUp s;
  CHECK(hold(s, stand, true, 1.0) == 0);
  CHECK(move(s, stand, seat, false, 1.0) == 0);  // sitting down
  CHECK(hold(s, seat, true, 1.5) == 0);
  CHECK_FALSE(s.armed());
  CHECK(hold(s, seat, true, 1.0) == 0);
  CHECK(s.armed());
  CHECK(move(s, seat, stand, false, 1.2) + hold(s, stand, true, 0.2) == 1);  // getting up (not "still")
  CHECK_FALSE(s.holding());                      // feet not held for 1 s after it
  CHECK(hold(s, stand, true, 3.0) == 0);         // once
  CHECK(s.holding());
  CHECK(s.count() == 1);
  // a bow: low for 1.5 s, too short a rest
  CHECK(move(s, stand, V(0.3, 1.20, -0.1), true, 0.5) == 0);
  CHECK(hold(s, V(0.3, 1.20, -0.1), true, 1.5) == 0);
  CHECK(move(s, V(0.3, 1.20, -0.1), stand, true, 0.5) + hold(s, stand, true, 1.0) == 0);
  // a jump from a stand (rested): 0.3 s more than 0.25 m up
  CHECK(hold(s, stand, true, 2.5) == 0);
  CHECK(s.armed());
  CHECK(move(s, stand, stand + V(0, 0.35, 0), true, 0.15) + move(s, stand + V(0, 0.35, 0), stand, true, 0.15) == 0);
  CHECK(hold(s, stand, true, 1.0) == 0);
  // stairs from a stand: 0.17 m up and 0.3 m ahead per 0.5 s step, walking
  CHECK(hold(s, stand, true, 2.5) == 0);
  CHECK(move(s, stand, stand + V(0, 0.85, -1.5), false, 2.5) + hold(s, stand + V(0, 0.85, -1.5), true, 1.0) == 0);
  // NaN changes nothing: seated and rested, a NaN burst, then up
  CHECK(hold(s, seat, true, 2.5) == 0);
  CHECK(hold(s, V(std::numeric_limits<double>::quiet_NaN(), 1.0, 0.0), true, 1.0) == 0);
  CHECK(s.armed());
  CHECK(hold(s, stand, true, 0.5) == 1);
  CHECK(s.count() == 2);
  CHECK_FALSE(s.holding());
  s.reset();  // a pipeline's reset(): like a new detector (the count kept)
  CHECK(s.holding());
  CHECK_FALSE(s.armed());
  trackers::StandUpConfig off;
  off.enabled = false;
  trackers::StandUp never(off);
  CHECK(hold(never, seat, true, 3.0) + hold(never, stand, true, 1.0) == 0);
}

TEST_CASE("a user who sits down for 5 s and stands up: one stand-up, finite output, no allocation") {
  const std::string dir = SPARSEBODY_WEIGHTS_DIR;
  check_stand_up<avatar::LoBSTrCompact>(avatar::LoBSTrCompact::load(dir + "/lobstr_compact.weights.json"), avatar::LoBSTrConfig{});
  check_stand_up<avatar::N3PDirect>(avatar::N3PDirect::load(dir + "/n3p"), avatar::N3PConfig{});
}
