// Recentring (trackers/recenter.hpp): the tracking space turned and shifted between two frames.
// The detector finds it exactly where it happens and nowhere in natural motion; the LoBSTr and
// Neural3Points pipelines on a device session of the CMU clip 01_01 stay with the user through a
// 90 deg / 0.5 m recentre (their output, turned back, within a few cm of the same session without
// it), with no allocation; the physics mode passes the recentre on to its direct pipeline.
#include <doctest/doctest.h>

#include <string>

#include "sparsebody/avatar/lobstr_pipeline.hpp"
#include "sparsebody/avatar/n3p_direct.hpp"
#include "sparsebody/avatar/n3p_physics.hpp"
#include "sparsebody/recordings/bvh.hpp"
#include "sparsebody/recordings/tracker_synthesis.hpp"
#include "sparsebody/trackers/recenter.hpp"
#include "support/alloc_counter.hpp"
#include "support/device_session.hpp"
#include "support/standing_stream.hpp"

using namespace sparsebody;

namespace {

// The frame turned by yaw a about world Y and shifted by d (what a recentre does to every tracker).
trackers::TrackerFrame recentred(trackers::TrackerFrame f, double a, const Eigen::Vector3d& d) {
  const Eigen::Quaterniond Y(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY()));
  for (auto& p : f.pose) {
    p.position = trackers::to_xr(Eigen::Vector3d(Y * trackers::to_eigen(p.position) + d));
    p.orientation = trackers::to_xr(Eigen::Quaterniond(Y * trackers::to_eigen(p.orientation)));
  }
  return f;
}

const std::vector<trackers::TrackerFrame>& device_session() { return sparsebody_test::device_session_01_01(); }

}  // namespace

TEST_CASE("recentre detector: the frame where the space turned and shifted, nothing in natural motion") {
  const auto& s = device_session();
  trackers::RecenterDetector plain;
  for (const auto& f : s) CHECK_FALSE(plain.push(f));  // jumps, turns, runs of 01_01: no recentre
  auto synthetic = sparsebody_test::session({{sparsebody_test::Phase::Stand, 1.0}, {sparsebody_test::Phase::Walk, 3.0}}, 72.0);
  trackers::RecenterDetector walk;
  for (const auto& f : synthetic) CHECK_FALSE(walk.push(f));
  struct Case { double yaw; Eigen::Vector3d shift; };
  for (const Case c : {Case{M_PI / 2, Eigen::Vector3d(0.5, 0, -0.2)}, Case{-0.6, Eigen::Vector3d::Zero()},
                       Case{0.0, Eigen::Vector3d(0.4, 0, 0)}, Case{3.0, Eigen::Vector3d(-2, 0.1, 1)}}) {
    CAPTURE(c.yaw);
    trackers::RecenterDetector d;
    int found = 0, at = -1;
    for (std::size_t i = 0; i < s.size(); ++i) {
      const auto f = i >= 500 ? recentred(s[i], c.yaw, c.shift) : s[i];
      if (d.push(f)) ++found, at = static_cast<int>(i);
    }
    CHECK(found == 1);
    CHECK(at == 500);
    CHECK(d.count() == 1);
  }
  // not a recentre: the headset alone jumps (a glitch: the sanitizer's), the controllers lost, or off
  trackers::RecenterDetector d;
  for (std::size_t i = 0; i < 700; ++i) {
    auto f = s[i];
    if (i >= 500) f.pose[0] = recentred(s[i], M_PI / 2, Eigen::Vector3d::Zero()).pose[0];
    CHECK_FALSE(d.push(f));
  }
  trackers::RecenterDetector lost;
  for (std::size_t i = 0; i < 700; ++i) {
    auto f = i >= 500 ? recentred(s[i], M_PI / 2, Eigen::Vector3d::Zero()) : s[i];
    f.valid[1] = f.valid[2] = f.valid[3] = false;
    CHECK_FALSE(lost.push(f));  // nothing to agree with the headset
  }
  trackers::RecenterConfig off;
  off.enabled = false;
  trackers::RecenterDetector no(off);
  for (std::size_t i = 0; i < 700; ++i) CHECK_FALSE(no.push(i >= 500 ? recentred(s[i], M_PI / 2, Eigen::Vector3d::Zero()) : s[i]));
}

// Mean and largest distance (m) over 2 s after a 90 deg / 0.5 m recentre 5 s in between the
// pipeline's output, turned back, and the same session's without the recentre.
struct Deviation { double first, mean, worst; };  // first: the mean over the first 0.5 s

template <class P, class W, class Cfg>
Deviation recentre_deviation(const W& w, Cfg cfg) {
  const auto& s = device_session();
  const std::size_t at = 72 * 5;  // 5 s in: the user is moving
  const double yaw = M_PI / 2;
  const Eigen::Vector3d shift(0.5, 0, -0.3);
  const Eigen::Quaterniond Y(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()));
  P a(w, cfg), b(w, cfg);
  double worst = 0, sum = 0, sum0 = 0;
  int n = 0, n0 = 0;
  for (std::size_t i = 0; i < s.size() && i < at + 72 * 2; ++i) {
    a.push(s[i]);
    const trackers::TrackerFrame f = i >= at ? recentred(s[i], yaw, shift) : s[i];
    {
      sparsebody_test::AllocationCounter count;
      b.push(f);
      CHECK(count.count() == 0);
    }
    if (i < at || !a.has_output() || !b.has_output()) continue;
    for (int j = 0; j < static_cast<int>(a.world().position.size()); ++j) {
      const Eigen::Vector3d back = Y.conjugate() * (b.world().position[j] - shift);  // b's output in a's world
      const double e = (back - a.world().position[j]).norm();
      worst = std::max(worst, e);
      sum += e, ++n;
      if (i < at + 36) sum0 += e, ++n0;
    }
  }
  CHECK(b.tracker_stream().recentres() == (cfg.sanitizer.recenter.enabled ? 1 : 0));
  CHECK(a.tracker_stream().recentres() == 0);
  return {sum0 / n0, sum / n, worst};
}

template <class P, class W, class Cfg>
void check_recentre(const W& w, const char* name) {
  Cfg on, off;
  off.sanitizer.recenter.enabled = false;
  const Deviation with = recentre_deviation<P>(w, on), without = recentre_deviation<P>(w, off);
  MESSAGE(std::string(name) << ": after a 90 deg / 0.5 m recentre (01_01 jumping), output from the same session's without it: mean "
                           << 100 * with.first << " cm over 0.5 s, " << 100 * with.mean << " over 2 s, max " << 100 * with.worst
                           << " (without the detector " << 100 * without.first << ", " << 100 * without.mean << ", max "
                           << 100 * without.worst << ")");
  CHECK(with.first < 0.8 * without.first);  // (validation walks: 4.6 / 6.3 cm against 61 / 69, README "Robustness")
  CHECK(with.mean < 0.85 * without.mean);
  CHECK(with.worst < 0.6 * without.worst);
  CHECK(with.worst < 0.35);
}

TEST_CASE("LoBSTr and Neural3Points stay with the user through a recentre of the tracking space") {
  const std::string dir = SPARSEBODY_WEIGHTS_DIR;
  check_recentre<avatar::LoBSTrCompact, std::shared_ptr<const avatar::LoBSTrCompact::Weights>, avatar::LoBSTrConfig>(
      avatar::LoBSTrCompact::load(dir + "/lobstr_compact.weights.json"), "LoBSTr");
  check_recentre<avatar::N3PDirect, avatar::N3PDirect::Weights, avatar::N3PConfig>(avatar::N3PDirect::load(dir + "/n3p"), "Neural3Points");
}

TEST_CASE("physics mode: its direct pipeline takes a recentred space at once, not as a jump to hold") {
  // The physics mode resamples for its direct pipeline and feeds it ticks; the front end's stream
  // finds the recentre, and direct mode's sanitizer must not hold the > 1 m headset jump it sees
  // (max_jump: held for relock_frames - 1 frames) as a glitch.
  const auto& s = device_session();
  const std::size_t at = 72 * 5;
  const double yaw = M_PI / 2;
  const Eigen::Vector3d shift(1.5, 0, -1.0);  // the headset moves > 1 m
  avatar::N3PPhysicsDefault p(avatar::N3PDirect::load(std::string(SPARSEBODY_WEIGHTS_DIR) + "/n3p"));
  int ticks_after = 0;
  double worst = 0, jump = 0;
  for (std::size_t i = 0; i < at + 36; ++i) {
    const trackers::TrackerFrame f = i >= at ? recentred(s[i], yaw, shift) : s[i];
    if (i == at) jump = (trackers::to_eigen(f.pose[0].position) - trackers::to_eigen(s[i - 1].pose[0].position)).norm();
    sparsebody_test::AllocationCounter count;
    const int n = p.push(f);
    CHECK(count.count() == 0);
    if (i < at || n == 0) continue;
    ++ticks_after;
    // the headset direct mode used on this tick, against the recentred input it came from
    const Eigen::Vector3d used = p.direct().tracker_stream().last_sanitized().pose[0].position;
    worst = std::max(worst, (used - trackers::to_eigen(f.pose[0].position)).norm());
  }
  MESSAGE("physics mode through a " << jump << " m headset recentre: direct mode's headset at most " << 100 * worst
                                    << " cm from the input over " << ticks_after << " ticks");
  CHECK(jump > 1.0);
  CHECK(p.recentres() == 1);
  CHECK(ticks_after > 10);
  CHECK(worst < 0.1);  // a tick interpolates at most one 72 Hz frame of motion; a held frame is > 1 m off
}
