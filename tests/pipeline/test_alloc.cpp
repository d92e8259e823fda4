// Zero heap allocations per frame in both run modes, contacts and IK included.
#include <doctest/doctest.h>

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
    {
      sparsebody_test::AllocationCounter c;
      for (std::size_t i = 1; i < frames.size(); ++i) steps += p.push(frames[i]);
      auto f = frames.back();
      f.time += 5.0;  // gap -> reset path
      f.valid[1] = false;
      steps += p.push(f);
      CHECK(c.count() == 0);
    }
    CHECK(steps == static_cast<int>(frames.size()));
  }
}
