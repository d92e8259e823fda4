// Zero heap allocations per frame in both run modes, contacts and IK included, through the shared
// front end (resampling, sanitising, the last-good guard both accepting and rejecting a frame).
#include <doctest/doctest.h>

#include <limits>

#include "common.hpp"
#include "sparsebody/avatar/lobstr_batch.hpp"
#include "support/alloc_counter.hpp"
#include "support/crowd_sessions.hpp"
#include "support/standing_stream.hpp"

using namespace sparsebody;

TEST_CASE("pipeline frames allocate nothing (streaming and window)") {
  const auto g = pipeline_test::read_json(pipeline_test::golden("lobstr_pipeline_small.golden.json"));
  const auto frames = pipeline_test::golden_frames(g);
  for (auto mode : {avatar::RunMode::Streaming, avatar::RunMode::Window}) {
    avatar::LoBSTrConfig cfg;
    cfg.mode = mode;
    pipeline_test::SmallPipeline p(pipeline_test::small_weights(), cfg);
    p.push(frames[0]);
    int steps = 0;
    features::Calibration nan_scale;
    nan_scale.scale = std::numeric_limits<double>::quiet_NaN();
    {
      sparsebody_test::AllocationCounter c;
      for (std::size_t i = 1; i < frames.size(); ++i) {
        trackers::TrackerFrame f = frames[i];
        f.time += 0.004;  // off the 30 Hz grid: the resampler interpolates
        steps += p.push(f);
      }
      auto f = frames.back();
      f.time += 5.0;  // gap -> reset path
      f.valid[1] = false;
      steps += p.push(f);
      p.set_calibration(nan_scale);  // a frame that is not finite: the guard keeps the last pose
      f.time += 1.0 / 30;
      steps += p.push(f);
      CHECK(c.count() == 0);
    }
    CHECK(p.has_output());
    CHECK(steps == static_cast<int>(frames.size()) + 1);
  }
}

// The automatic calibration inside push(): standing windows found, refused, skipped, broken by a
// NaN burst, recalibrate(): none of it allocates.
TEST_CASE("pipeline frames allocate nothing with the automatic calibration finding standing windows") {
  using sparsebody_test::Phase;
  auto frames = sparsebody_test::session({{Phase::Walk, 1.0, 1.70}, {Phase::Stand, 2.5, 1.70}, {Phase::Walk, 1.0, 1.70},
                                          {Phase::Stand, 2.5, 1.76}, {Phase::Walk, 1.0, 1.76}, {Phase::Stand, 2.5, 1.20},
                                          {Phase::Walk, 1.0, 1.76}, {Phase::Stand, 2.5, 2.4}, {Phase::Walk, 1.0, 1.76}},
                                         72.0);
  for (std::size_t i = 400; i < 405; ++i) frames[i].pose[0].position.x = std::numeric_limits<float>::quiet_NaN();
  pipeline_test::SmallPipeline p(pipeline_test::small_weights());
  for (int i = 0; i < 3; ++i) p.push(frames[static_cast<std::size_t>(i)]);
  {
    sparsebody_test::AllocationCounter c;
    for (std::size_t i = 3; i < frames.size(); ++i) {
      p.push(frames[i]);
      if (i == frames.size() / 2) p.recalibrate();
    }
    CHECK(c.count() == 0);
  }
  CHECK(p.calibration_report().status == features::CalibrationStatus::Calibrated);
  CHECK(p.body_proportions().leg != 1.0);  // the output skeleton was re-proportioned in there too
  CHECK(p.calibration_report().skipped + p.calibration_report().refused >= 1);
  CHECK(p.has_output());
}

TEST_CASE("pipeline frames allocate nothing when a bent first stand is raised (AutoCalibration::rise)") {
  using sparsebody_test::Phase;
  // crouched and still at 1.55 m, then walking upright at 1.72 m: the estimate is raised mid-walk
  const auto frames = sparsebody_test::session({{Phase::Stand, 2.0, 1.55}, {Phase::Walk, 3.0, 1.72}}, 72.0);
  pipeline_test::SmallPipeline p(pipeline_test::small_weights());
  for (int i = 0; i < 3; ++i) p.push(frames[static_cast<std::size_t>(i)]);
  {
    sparsebody_test::AllocationCounter c;
    for (std::size_t i = 3; i < frames.size(); ++i) p.push(frames[i]);
    CHECK(c.count() == 0);
  }
  CHECK(p.calibration_report().raised == 1);
  CHECK(p.has_output());
}

TEST_CASE("pipeline frames allocate nothing while the legs are sized and the arms lengthened (body proportions)") {
  using sparsebody_test::Phase;
  auto frames = sparsebody_test::session({{Phase::Stand, 3.0, 1.75, 0.66}}, 72.0);  // a long-legged belt
  sparsebody_test::reach_out(frames, 1.0, 0.56, 72.0);                            // arms beyond the standard reach
  pipeline_test::SmallPipeline p(pipeline_test::small_weights());
  for (int i = 0; i < 3; ++i) p.push(frames[static_cast<std::size_t>(i)]);
  {
    sparsebody_test::AllocationCounter c;
    for (std::size_t i = 3; i < frames.size(); ++i) p.push(frames[i]);
    CHECK(c.count() == 0);
  }
  CHECK(p.body_proportions().leg > 1.03);
  CHECK(p.body_proportions().arm > 1.03);
}

// LoBSTrBatch (avatar/lobstr_batch.hpp): one call for 6 users, shipped weights in float and int8,
// through calibrations, a lost controller, a NaN burst and a restart.
TEST_CASE("a LoBSTr batch step allocates nothing") {
  constexpr int n = 6;
  avatar::LoBSTrBatch<avatar::LoBSTrCompactQ8> crowd(avatar::LoBSTrCompactQ8::load(SPARSEBODY_LOBSTR_WEIGHTS), n);
  avatar::LoBSTrBatch<avatar::LoBSTrCompact> crowd_f(avatar::LoBSTrCompact::load(SPARSEBODY_LOBSTR_WEIGHTS), n);
  std::vector<std::vector<trackers::TrackerFrame>> in;
  for (int u = 0; u < n; ++u) in.push_back(sparsebody_test::crowd_user_frames(u, true));
  sparsebody_test::step_crowds(in, 0, 1, crowd, crowd_f);
  {
    sparsebody_test::AllocationCounter c;
    sparsebody_test::step_crowds(in, 1, in[0].size(), crowd, crowd_f);
    CHECK(c.count() == 0);
  }
  for (int u = 0; u < n; ++u) CHECK(crowd[u].has_output());
}
