// The pipelines' shared front end: TrackerStream (resampling to model ticks, gap flag, sanitising
// with the model period), PoseOutput (the last-good guard) and its use in the LoBSTr pipeline.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "common.hpp"
#include "sparsebody/pose/pose_output.hpp"
#include "sparsebody/trackers/tracker_stream.hpp"

using namespace sparsebody;

namespace {
trackers::TrackerFrame head_frame(double t, bool valid = true) {
  trackers::TrackerFrame f;
  f.time = t;
  f.pose[0].position = {0.0f, 1.6f, static_cast<float>(0.1 * t)};
  f.valid[0] = valid;
  return f;
}
}  // namespace

TEST_CASE("tracker stream: any-rate frames become model ticks; a time jump is a gap") {
  trackers::TrackerStream stream(30.0);
  CHECK(stream.period() == doctest::Approx(1.0 / 30));
  std::vector<double> ticks;
  std::vector<bool> gaps;
  auto on_tick = [&](const trackers::TrackerFrame& tick, bool gap) {
    ticks.push_back(tick.time);
    gaps.push_back(gap);
  };
  int n = 0;
  for (int i = 0; i <= 90; ++i) n += stream.push(head_frame(i / 90.0), on_tick);  // 1 s at 90 Hz
  CHECK(n == 31);
  CHECK(ticks.back() == doctest::Approx(1.0));
  n = stream.push(head_frame(3.0), on_tick);  // 2 s later: the clock restarts, flagged
  CHECK(n == 1);
  CHECK(gaps.front() == false);  // the very first tick is no gap (nothing ran before it)
  CHECK(gaps.back() == true);
  CHECK(ticks.back() == 3.0);
}

TEST_CASE("tracker stream: ticks are sanitised with the model period (headset loss resets after max_hold)") {
  trackers::SanitizerConfig cfg;
  cfg.max_hold = 0.5;
  trackers::TrackerStream stream(30.0, cfg);
  CHECK(stream.sanitize(head_frame(0)).usable);
  int lost = 0;
  while (!stream.sanitize(head_frame(0, false)).reset) ++lost;
  CHECK(lost == 15);  // 16 ticks of 1/30 s exceed 0.5 s
  stream.reset();
  CHECK_FALSE(stream.sanitize(head_frame(0, false)).usable);
}

TEST_CASE("pose output: a finite frame is handed out, a non-finite one keeps the last") {
  pose::PoseOutput out;
  out.resize(3);
  CHECK_FALSE(out.has_output());
  out.pose().root_position.x() = std::numeric_limits<double>::quiet_NaN();
  CHECK_FALSE(out.commit());  // nothing good yet: no output, the (identity) start pose back
  CHECK_FALSE(out.has_output());
  CHECK(out.pose().root_position.isZero());
  out.pose().root_position = Eigen::Vector3d(1, 2, 3);
  out.world().position[2] = Eigen::Vector3d(4, 5, 6);
  CHECK(out.commit());
  CHECK(out.has_output());
  out.world().position[2].y() = std::numeric_limits<double>::infinity();
  out.pose().root_position.z() = 9;
  CHECK_FALSE(out.commit());
  CHECK(out.has_output());
  CHECK(out.pose().root_position == Eigen::Vector3d(1, 2, 3));
  CHECK(out.world().position[2] == Eigen::Vector3d(4, 5, 6));
  out.invalidate();
  CHECK_FALSE(out.has_output());
  CHECK(pose::all_finite(out.pose(), out.world()));
}

TEST_CASE("LoBSTr: a frame that would not be finite keeps the last pose (the front end's guard)") {
  const auto g = pipeline_test::read_json(pipeline_test::golden("lobstr_pipeline_small.golden.json"));
  const auto frames = pipeline_test::golden_frames(g);
  pipeline_test::SmallPipeline p(pipeline_test::small_weights());
  for (int i = 0; i < 20; ++i) p.push(frames[i]);
  REQUIRE(p.has_output());
  const pose::WorldPose last = p.world();
  features::Calibration bad;
  bad.scale = std::numeric_limits<double>::quiet_NaN();  // every position NaN
  p.set_calibration(bad);
  for (int i = 20; i < 25; ++i) {
    REQUIRE(p.push(frames[i]) == 1);
    CHECK(p.has_output());
    for (std::size_t j = 0; j < last.position.size(); ++j) REQUIRE(p.world().position[j] == last.position[j]);
  }
  p.set_calibration(features::Calibration{});
  p.push(frames[25]);
  CHECK(p.has_output());
  CHECK(pose::all_finite(p.pose(), p.world()));
  CHECK(p.world().position[0] != last.position[0]);
}

TEST_CASE("front end: push(frame, after) runs after(tick, gap) once after each step") {
  const auto g = pipeline_test::read_json(pipeline_test::golden("lobstr_pipeline_small.golden.json"));
  const auto frames = pipeline_test::golden_frames(g);
  pipeline_test::SmallPipeline a(pipeline_test::small_weights()), b(pipeline_test::small_weights());
  int after = 0, gaps = 0;
  long long steps_seen = 0;
  for (std::size_t i = 0; i < 40; ++i) {
    trackers::TrackerFrame f = frames[i];
    if (i >= 20) f.time += 3.0;  // a time jump at frame 20
    const int na = a.push(f);
    const int nb = b.push(f, [&](const trackers::TrackerFrame&, bool gap) {
      ++after;
      gaps += gap;
      steps_seen = b.frames();  // the step has run when after() is called
    });
    REQUIRE(na == nb);
    CHECK(steps_seen == b.frames());
  }
  CHECK(after == static_cast<int>(b.frames()));
  CHECK(gaps == 1);
  CHECK(a.frames() == b.frames());
  for (std::size_t j = 0; j < a.world().position.size(); ++j) CHECK(a.world().position[j] == b.world().position[j]);
}
