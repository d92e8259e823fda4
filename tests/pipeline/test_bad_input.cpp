// Bad tracker input has defined behaviour and never produces NaN: NaN/Inf, non-unit quaternions,
// invalid trackers, time gaps, 1 m jumps, missing pelvis.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>

#include "common.hpp"

using namespace sparsebody;

namespace {
bool finite_pose(const pipeline_test::SmallPipeline& p) {
  if (!p.pose().root_position.allFinite()) return false;
  for (const auto& q : p.pose().local)
    if (!q.coeffs().allFinite()) return false;
  for (const auto& x : p.world().position)
    if (!x.allFinite()) return false;
  for (int i = 0; i < 52; ++i)
    if (!std::isfinite(p.network_output()[i])) return false;
  return true;
}

struct Run {
  pipeline_test::SmallPipeline p{pipeline_test::small_weights()};
  std::vector<trackers::TrackerFrame> frames;
  Run() {
    const auto g = pipeline_test::read_json(pipeline_test::golden("lobstr_pipeline_small.golden.json"));
    frames = pipeline_test::golden_frames(g);
    features::Calibration c;
    c.scale = g["scale"].get<double>();
    p.set_calibration(c);
  }
};
}  // namespace

TEST_CASE("NaN, Inf and non-unit quaternions: the tracker is held, the output stays finite") {
  Run r;
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  for (std::size_t i = 0; i < r.frames.size(); ++i) {
    auto f = r.frames[i];
    if (i % 7 == 3) f.pose[0].position.x = nan;
    if (i % 11 == 5) f.pose[3].orientation.w = inf;
    if (i % 13 == 6) f.pose[1].orientation = {0, 0, 0, 0};
    if (i % 17 == 8) f.pose[2].orientation = {0.5f, 0.5f, 0.5f, 2.0f};  // norm 2.2: rejected
    if (i % 19 == 9) f.time = std::numeric_limits<double>::quiet_NaN();  // dropped
    r.p.push(f);
    REQUIRE(finite_pose(r.p));
  }
  CHECK(r.p.has_output());
}

TEST_CASE("held tracker: an invalid tracker keeps its last good world pose") {
  Run r;
  trackers::TrackerSanitizer san;
  for (std::size_t i = 0; i < 40; ++i) san.process(r.frames[i], 1.0 / 30);
  auto f = r.frames[40];
  f.valid[1] = false;            // left hand lost
  f.pose[1].position.x += 5.0f;  // garbage where invalid
  const auto& s = san.process(f, 1.0 / 30);
  CHECK_FALSE(s.measured[1]);
  CHECK(s.measured[0]);
  CHECK((s.pose[1].position - trackers::to_eigen(r.frames[39].pose[1].position)).norm() < 1e-6);
  for (std::size_t i = 0; i < 40; ++i) r.p.push(r.frames[i]);
  r.p.push(f);
  CHECK(finite_pose(r.p));
}

TEST_CASE("a 1 m jump in one frame is rejected as a glitch; a lasting move is accepted with a reset") {
  Run r;
  trackers::TrackerSanitizer san;
  for (std::size_t i = 0; i < 30; ++i) san.process(r.frames[i], 1.0 / 30);
  auto f = r.frames[30];
  f.pose[2].position.y += 1.5f;  // right hand 1.5 m up for one frame
  const auto& s = san.process(f, 1.0 / 30);
  CHECK_FALSE(s.measured[2]);
  CHECK_FALSE(s.reset);
  CHECK((s.pose[2].position - trackers::to_eigen(r.frames[29].pose[2].position)).norm() < 1e-6);
  // the whole body moves 2 m (recentred space) for good: on the 3rd frame it is accepted, with a reset
  int resets = 0;
  for (std::size_t i = 31; i < 36; ++i) {
    auto g = r.frames[i];
    for (int k = 0; k < 4; ++k) g.pose[k].position.x += 2.0f;
    resets += san.process(g, 1.0 / 30).reset;
  }
  CHECK(resets >= 1);
  CHECK(std::abs(san.process(r.frames[36], 1.0 / 30).pose[0].position.x() - r.frames[36].pose[0].position.x) > 1.0);
  // and through the pipeline: finite, the root follows the moved trackers
  for (std::size_t i = 0; i < 31; ++i) r.p.push(i == 30 ? f : r.frames[i]);
  for (std::size_t i = 31; i < 40; ++i) {
    auto g = r.frames[i];
    for (int k = 0; k < 4; ++k) g.pose[k].position.x += 2.0f;
    r.p.push(g);
    REQUIRE(finite_pose(r.p));
  }
  const double s_ = r.p.calibration().scale;
  CHECK(std::abs(r.p.pose().root_position.x() - (r.frames[39].pose[3].position.x + 2.0) * s_) < 1e-3);
}

TEST_CASE("time gap: state reset, first frame after the gap has zero velocities") {
  Run r;
  for (std::size_t i = 0; i < 30; ++i) r.p.push(r.frames[i]);
  auto f = r.frames[60];
  f.time = r.frames[29].time + 2.0;  // 2 s without frames
  CHECK(r.p.push(f) == 1);
  for (int c = 0; c < 3; ++c) CHECK(r.p.features()[c] == 0.0f);
  for (int c = 9; c < 12; ++c) CHECK(r.p.features()[c] == 0.0f);
  CHECK(finite_pose(r.p));
}

TEST_CASE("headset lost for longer than the hold time: no crash, output held, then recovers") {
  Run r;
  for (std::size_t i = 0; i < 30; ++i) r.p.push(r.frames[i]);
  for (std::size_t i = 30; i < 60; ++i) {
    auto f = r.frames[i];
    f.valid = {false, false, false, false};
    r.p.push(f);
    REQUIRE(finite_pose(r.p));
  }
  for (std::size_t i = 60; i < 90; ++i) r.p.push(r.frames[i]);
  CHECK(r.p.has_output());
  CHECK(finite_pose(r.p));
}

TEST_CASE("no pelvis tracker at all: the pelvis is placed under the headset; output finite") {
  Run r;
  for (std::size_t i = 0; i < r.frames.size(); ++i) {
    auto f = r.frames[i];
    f.valid[3] = false;
    r.p.push(f);
    REQUIRE(finite_pose(r.p));
  }
  CHECK(r.p.has_output());
  CHECK(r.p.pose().root_position.y() > 0.3);
}

TEST_CASE("no valid input yet: no output") {
  Run r;
  auto f = r.frames[0];
  f.valid = {false, false, false, false};
  r.p.push(f);
  CHECK_FALSE(r.p.has_output());
}

TEST_CASE("a controller put down out of reach is held, and taken back without a jump or a reset") {
  Run r;
  trackers::TrackerSanitizer san;
  auto on_table = [](trackers::TrackerFrame f) {  // the left controller 2 m from the headset, on a table
    f.pose[1].position = trackers::to_xr(Eigen::Vector3d(trackers::to_eigen(f.pose[0].position) + Eigen::Vector3d(2.0, -0.8, 0.5)));
    return f;
  };
  // from the first frame: never in a hand yet, so at the headset (the sanitizer's "never seen")
  for (std::size_t i = 0; i < 20; ++i) {
    const auto& s = san.process(on_table(r.frames[i]), 1.0 / 30);
    CHECK_FALSE(s.measured[1]);
    CHECK(s.measured[2]);
    CHECK((s.pose[1].position - s.pose[0].position).norm() < 1e-9);
  }
  // picked up: measured at once, no reset
  for (std::size_t i = 20; i < 40; ++i) {
    const auto& s = san.process(r.frames[i], 1.0 / 30);
    CHECK(s.measured[1]);
    CHECK_FALSE(s.reset);
  }
  // put down again: held where it was last in a hand
  for (std::size_t i = 40; i < 50; ++i) {
    const auto& s = san.process(on_table(r.frames[i]), 1.0 / 30);
    CHECK_FALSE(s.measured[1]);
    CHECK((s.pose[1].position - trackers::to_eigen(r.frames[39].pose[1].position)).norm() < 1e-6);
  }
  CHECK(san.process(r.frames[50], 1.0 / 30).measured[1]);
  CHECK_FALSE(san.last().reset);
  trackers::SanitizerConfig off;  // the check off: the table is where the hand is
  off.max_controller_distance = 0;
  trackers::TrackerSanitizer all(off);
  CHECK(all.process(on_table(r.frames[0]), 1.0 / 30).measured[1]);
  for (std::size_t i = 0; i < r.frames.size(); ++i) {
    r.p.push(i < 20 || (i >= 40 && i < 50) ? on_table(r.frames[i]) : r.frames[i]);
    REQUIRE(finite_pose(r.p));
  }
}
