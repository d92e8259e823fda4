// Controllers in the other hands (trackers/controller_swap.hpp): the detector decides from hands
// that hang crossed, never from natural motion or a pose held in front of the chest; the LoBSTr and
// Neural3Points pipelines on a device session of the CMU clip 01_01 whose controllers were picked
// up the wrong way round give, once the swap is found, what the same session gives with the
// controllers the right way round, with no allocation.
#include <doctest/doctest.h>

#include <string>

#include "sparsebody/avatar/lobstr_pipeline.hpp"
#include "sparsebody/avatar/n3p_direct.hpp"
#include "sparsebody/recordings/bvh.hpp"
#include "sparsebody/recordings/tracker_synthesis.hpp"
#include "sparsebody/trackers/controller_swap.hpp"
#define SPARSEBODY_ALLOC_COUNTER_USE_ONLY  // test_recenter.cpp defines the operators
#include "support/alloc_counter.hpp"
#include "support/device_session.hpp"
#include "support/standing_stream.hpp"

using namespace sparsebody;
using sparsebody_test::Phase;

namespace {

trackers::TrackerFrame swapped(trackers::TrackerFrame f) {
  std::swap(f.pose[1], f.pose[2]);
  std::swap(f.valid[1], f.valid[2]);
  return f;
}

// Time of each decision of a detector fed frames (swapped from `from` on).
std::vector<double> decisions(const std::vector<trackers::TrackerFrame>& s, std::size_t from,
                              trackers::ControllerSwapConfig cfg = {},
                              Eigen::Quaterniond head_offset = trackers::ControllerSwapDetector::openxr_head_offset()) {
  trackers::ControllerSwapDetector d(cfg);
  std::vector<double> at;
  for (std::size_t i = 0; i < s.size(); ++i)
    if (d.push(i >= from ? swapped(s[i]) : s[i], head_offset)) at.push_back(s[i].time);
  CHECK(d.count() == static_cast<int>(at.size()));
  CHECK(d.swapped() == (at.size() % 2 == 1));
  return at;
}

const std::vector<trackers::TrackerFrame>& device_session() { return sparsebody_test::device_session_01_01(); }

}  // namespace

TEST_CASE("controller swap detector: crossed hanging hands, and nothing else") {
  const auto walk = sparsebody_test::session({{Phase::Stand, 2.0}, {Phase::Walk, 14.0}, {Phase::Stand, 2.0}}, 72);
  const std::size_t n = walk.size();
  CHECK(decisions(walk, n).empty());  // the right way round: never
  {
    const auto at = decisions(walk, 0);  // swapped from the first frame
    REQUIRE(at.size() == 1);
    CHECK(at[0] == doctest::Approx(1.5).epsilon(0.05));  // evidence (1.5 s) of hands hanging crossed
  }
  {
    const auto at = decisions(walk, 72 * 5);  // the controllers changed hands 5 s in
    REQUIRE(at.size() == 1);
    CHECK(at[0] > 5.0);
    CHECK(at[0] < 15.0);
    MESSAGE("controllers changed hands 5 s into a session: found at " << at[0] << " s");
  }
  {
    // put down on a table for 2 s (both 2 m from the headset), picked up the other way round 8 s in:
    // the tallies start again at the put-down, so it is found 1.5 s after the pick-up
    auto table = walk;
    for (std::size_t i = 72 * 6; i < 72 * 8; ++i)
      for (int k = 1; k < 3; ++k)
        table[i].pose[k].position = trackers::to_xr(Eigen::Vector3d(trackers::to_eigen(table[i].pose[0].position) + Eigen::Vector3d(2, -0.8, 0)));
    const auto at = decisions(table, 72 * 8);
    REQUIRE(at.size() == 1);
    CHECK(at[0] == doctest::Approx(9.5).epsilon(0.03));
    MESSAGE("controllers put down 6-8 s and picked up the other way round: found at " << at[0] << " s");
    trackers::ControllerSwapConfig no_restart;
    no_restart.put_down_time = 1e9;
    const auto late = decisions(table, 72 * 8, no_restart);
    REQUIRE(late.size() == 1);
    CHECK(late[0] > at[0] + 2.0);
  }
  trackers::ControllerSwapConfig off;
  off.enabled = false;
  CHECK(decisions(walk, 0, off).empty());

  // Trackers in the body convention (the head faces +Z): right with the identity head offset, and
  // every hand crossed if taken for an OpenXR headset.
  auto body = walk;
  const Eigen::Quaterniond half(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()));
  for (auto& f : body)
    for (auto& p : f.pose) p.orientation = trackers::to_xr(Eigen::Quaterniond(trackers::to_eigen(p.orientation) * half));
  CHECK(decisions(body, n, {}, Eigen::Quaterniond::Identity()).empty());
  CHECK(decisions(body, n).size() == 1);

  // Arms crossed in front of the chest for 10 s (hands 0.3 m under the headset): no evidence.
  auto chest = sparsebody_test::session({{Phase::Stand, 12.0}}, 72);
  for (auto& f : chest)
    for (int k = 1; k < 3; ++k) {
      Eigen::Vector3d p = trackers::to_eigen(f.pose[k].position);
      p.y() = f.pose[0].position.y - 0.3;
      f.pose[k].position = trackers::to_xr(p);
    }
  CHECK(decisions(chest, 0).empty());
  // Hands crossed low for 1 s now and then (a gesture): not enough.
  auto brief = sparsebody_test::session({{Phase::Walk, 20.0}}, 72);
  for (std::size_t i = 0; i < brief.size(); ++i)
    if (i % (72 * 5) < 72) brief[i] = swapped(brief[i]);
  CHECK(decisions(brief, brief.size()).empty());
  // Lost controllers, NaN time stamps and NaN poses add nothing and break nothing.
  auto bad = walk;
  for (std::size_t i = 0; i < bad.size(); i += 3) bad[i].valid[1] = false;
  for (std::size_t i = 1; i < bad.size(); i += 7) bad[i].pose[2].position.x = std::nanf("");
  bad[50].time = std::nan("");
  const auto at = decisions(bad, 0);
  REQUIRE(at.size() == 1);
  CHECK(at[0] < 3.5);
}

// Mean distance (m) over every joint and over the hands, from 4 s on, between the pipeline's output
// on the session with swapped controllers and on the same session the right way round.
struct Deviation { double all, hands; int swaps; };

template <class P, class W, class Cfg>
Deviation swap_deviation(const W& w, Cfg cfg, int hand_l, int hand_r) {
  const auto& s = device_session();
  P a(w, cfg), b(w, cfg);
  double sum = 0, sum_h = 0;
  int n = 0, n_h = 0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    a.push(s[i]);
    {
      sparsebody_test::AllocationCounter count;
      b.push(swapped(s[i]));
      CHECK(count.count() == 0);
    }
    if (s[i].time < 4.0 || !a.has_output() || !b.has_output()) continue;
    for (int j = 0; j < static_cast<int>(a.world().position.size()); ++j) {
      const double e = (b.world().position[j] - a.world().position[j]).norm();
      sum += e, ++n;
      if (j == hand_l || j == hand_r) sum_h += e, ++n_h;
    }
  }
  CHECK(a.controller_swaps() == 0);
  return {sum / n, sum_h / n_h, b.controller_swaps()};
}

template <class P, class W, class Cfg>
void check_swap(const W& w, const char* name) {
  Cfg on, off;
  off.sanitizer.controller_swap.enabled = false;
  const P probe(w, on);
  const pose::JointMap map = pose::JointMap::from_names(probe.skeleton(), name);
  const int l = map.joint[static_cast<int>(pose::Role::HandL)], r = map.joint[static_cast<int>(pose::Role::HandR)];
  const Deviation with = swap_deviation<P>(w, on, l, r), without = swap_deviation<P>(w, off, l, r);
  MESSAGE(std::string(name) << ": 01_01 with the controllers in the other hands, output from 4 s on against the right way round: "
                           << 100 * with.all << " cm mean, hands " << 100 * with.hands << " cm (without the check "
                           << 100 * without.all << ", hands " << 100 * without.hands << ")");
  CHECK(with.swaps == 1);
  CHECK(without.swaps == 0);
  CHECK(without.hands > 0.2);
  CHECK(with.hands < 0.05);
  CHECK(with.all < 0.03);
}

TEST_CASE("LoBSTr and Neural3Points take controllers held in the other hands") {
  const std::string dir = SPARSEBODY_WEIGHTS_DIR;
  check_swap<avatar::LoBSTrCompact, std::shared_ptr<const avatar::LoBSTrCompact::Weights>, avatar::LoBSTrConfig>(
      avatar::LoBSTrCompact::load(dir + "/lobstr_compact.weights.json"), "LoBSTr");
  check_swap<avatar::N3PDirect, avatar::N3PDirect::Weights, avatar::N3PConfig>(avatar::N3PDirect::load(dir + "/n3p"), "Neural3Points");
}

TEST_CASE("an exchange moves the calibration's controller offsets with the devices; reset() forgets both") {
  const auto& s = device_session();
  auto p = std::make_unique<avatar::LoBSTrCompact>(avatar::LoBSTrCompact::load(std::string(SPARSEBODY_WEIGHTS_DIR) + "/lobstr_compact.weights.json"));
  features::Calibration c;  // an explicit calibration with distinct controller offsets (it survives reset())
  c.offset[1] = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()));
  c.offset[2] = Eigen::Quaterniond(Eigen::AngleAxisd(-0.5, Eigen::Vector3d::UnitZ()));
  c.offset[0] = trackers::ControllerSwapDetector::openxr_head_offset();
  p->set_calibration(c);
  std::size_t i = 0;
  for (; i < s.size() && p->controller_swaps() == 0; ++i) p->push(swapped(s[i]));
  REQUIRE(p->controllers_swapped());
  while (i < s.size() && p->push(swapped(s[i++])) == 0) {}  // until the first tick of the new roles has run
  CHECK(p->calibration().offset[1].isApprox(c.offset[2]));
  CHECK(p->calibration().offset[2].isApprox(c.offset[1]));
  CHECK(p->calibration().position_offset[1].isApprox(c.position_offset[1]));  // the hands' grips stay
  p->reset();
  CHECK_FALSE(p->controllers_swapped());
  CHECK(p->calibration().offset[1].isApprox(c.offset[1]));
  CHECK(p->calibration().offset[2].isApprox(c.offset[2]));
}
