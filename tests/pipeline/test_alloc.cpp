// Zero heap allocations per frame in both run modes, contacts and IK included, through the shared
// front end (resampling, sanitising, the last-good guard both accepting and rejecting a frame).
#include <doctest/doctest.h>

#include <limits>

#include "common.hpp"
#include "support/alloc_counter.hpp"

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
