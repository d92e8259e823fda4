// Zero heap allocations per frame: the pipeline (the shared front end's resampler, sanitizer and
// output pose, calibration, predictor, direct-mode IK, head height) over clean frames, HMD-only
// frames, a headset far below and above the body, and bad input.
#include <doctest/doctest.h>

#include "n3p/common.hpp"
#include "support/alloc_counter.hpp"
#include "support/crowd_sessions.hpp"
#include "support/standing_stream.hpp"
#include "sparsebody/avatar/n3p_batch.hpp"

using namespace sparsebody;

TEST_CASE("n3p pipeline: no allocation per frame") {
  const auto g = n3p_test::read_json(n3p_test::golden_dir() + "/n3p_small.golden.json");
  const auto w = n3p_test::SmallPipeline::load(n3p_test::small_prefix());
  avatar::N3PConfig c;
  c.contact_threshold = 0.0;
  n3p_test::SmallPipeline p(w, c);
  std::vector<trackers::TrackerFrame> frames;
  for (int t = 0; t < g["frames"].get<int>(); ++t) frames.push_back(n3p_test::golden_frame(g, t));
  frames[20].pose[0].position.x = std::numeric_limits<float>::quiet_NaN();
  frames[21].valid[0] = false;
  for (int t = 0; t < 3; ++t) p.push(frames[t]);  // warm-up
  features::n3p::N3PCalibration nan_scale;
  nan_scale.base.scale = std::numeric_limits<double>::quiet_NaN();
  long long n = 0;
  {
    sparsebody_test::AllocationCounter counter;
    for (std::size_t t = 3; t < frames.size(); ++t) {
      trackers::TrackerFrame f = frames[t];
      f.time += 0.004;  // off the 30 Hz grid: the resampler interpolates
      // frames 40-59 kneeling, 60-79 on a platform: head_height moves the body down (the legs
      // bent to the ankles) and up
      const float dy = t >= 40 && t < 60 ? -0.8f : t >= 60 && t < 80 ? 0.8f : 0.0f;
      for (auto& pose : f.pose) pose.position.y += dy;
      // frames 30-31 under a NaN calibration scale: the predictor rejects them, the last pose stays
      if (t == 30) p.set_calibration(nan_scale);
      if (t == 32) p.set_calibration(features::n3p::N3PCalibration{});
      p.push(f);
    }
    n = counter.count();
  }
  CHECK(n == 0);
  CHECK(p.has_output());
}

TEST_CASE("n3p pipeline with int8 weights (nn/int8.hpp): no allocation per frame, finite output") {
  using Q8Pipeline = avatar::N3PPipeline<float, 16, 24, 24, nn::q8>;
  const auto g = n3p_test::read_json(n3p_test::golden_dir() + "/n3p_small.golden.json");
  Q8Pipeline p(Q8Pipeline::load(n3p_test::small_prefix()));
  std::vector<trackers::TrackerFrame> frames;
  for (int t = 0; t < g["frames"].get<int>(); ++t) frames.push_back(n3p_test::golden_frame(g, t));
  frames[20].pose[1].position.y = std::numeric_limits<float>::quiet_NaN();
  for (int t = 0; t < 3; ++t) p.push(frames[t]);
  long long n = 0;
  {
    sparsebody_test::AllocationCounter counter;
    for (std::size_t t = 3; t < frames.size(); ++t) {
      p.push(frames[t]);
      for (const auto& x : p.world().position) REQUIRE(x.allFinite());
    }
    n = counter.count();
  }
  CHECK(n == 0);
  CHECK(p.has_output());
}

// The automatic calibration inside push() (standing windows found, refined, skipped, refused,
// recalibrate()) allocates nothing.
TEST_CASE("n3p pipeline: no allocation per frame with the automatic calibration finding standing windows") {
  using sparsebody_test::Phase;
  auto frames = sparsebody_test::session({{Phase::Walk, 1.0, 1.70}, {Phase::Stand, 2.5, 1.70}, {Phase::Walk, 1.0, 1.70},
                                          {Phase::Stand, 2.5, 1.76}, {Phase::Walk, 1.0, 1.76}, {Phase::Stand, 2.5, 1.20},
                                          {Phase::Walk, 1.0, 1.76}, {Phase::Stand, 2.5, 2.4}, {Phase::Walk, 1.0, 1.76}},
                                         72.0, 0.3, false);
  for (std::size_t i = 400; i < 405; ++i) frames[i].pose[0].position.x = std::numeric_limits<float>::quiet_NaN();
  n3p_test::SmallPipeline p(n3p_test::SmallPipeline::load(n3p_test::small_prefix()));
  for (int i = 0; i < 3; ++i) p.push(frames[static_cast<std::size_t>(i)]);
  long long n = 0;
  {
    sparsebody_test::AllocationCounter counter;
    for (std::size_t i = 3; i < frames.size(); ++i) {
      p.push(frames[i]);
      if (i == frames.size() / 2) p.recalibrate();
    }
    n = counter.count();
  }
  CHECK(n == 0);
  CHECK(p.calibration_report().status == features::CalibrationStatus::Calibrated);
  CHECK(p.has_output());
}

TEST_CASE("n3p pipeline: no allocation per frame while the arms are lengthened (arm reach), shipped weights") {
  using sparsebody_test::Phase;
  auto frames = sparsebody_test::session({{Phase::Stand, 3.0, 1.75}}, 72.0);
  sparsebody_test::reach_out(frames, 1.0, 0.50, 72.0);  // controllers beyond the standard arms' reach
  avatar::N3PDirect p(avatar::N3PDirect::load(std::string(SPARSEBODY_SOURCE_DIR) + "/examples/weights/n3p"));
  for (int i = 0; i < 3; ++i) p.push(frames[static_cast<std::size_t>(i)]);
  long long n = 0;
  {
    sparsebody_test::AllocationCounter counter;
    for (std::size_t i = 3; i < frames.size(); ++i) p.push(frames[i]);
    n = counter.count();
  }
  CHECK(n == 0);
  CHECK(p.body_proportions().arm > 1.03);
}

// N3PBatch (avatar/n3p_batch.hpp): one call for 6 users, shipped weights in float and int8,
// through calibrations, a lost controller, a NaN burst and a restart.
TEST_CASE("n3p batch: a batch step allocates nothing") {
  constexpr int n = 6;
  const std::string prefix = std::string(SPARSEBODY_SOURCE_DIR) + "/examples/weights/n3p";
  avatar::N3PBatch<avatar::N3PDirectQ8> crowd(avatar::N3PDirectQ8::load(prefix), n);
  avatar::N3PBatch<avatar::N3PDirect> crowd_f(avatar::N3PDirect::load(prefix), n);
  std::vector<std::vector<trackers::TrackerFrame>> in;
  for (int u = 0; u < n; ++u) in.push_back(sparsebody_test::crowd_user_frames(u, false));
  sparsebody_test::step_crowds(in, 0, 1, crowd, crowd_f);
  {
    sparsebody_test::AllocationCounter c;
    sparsebody_test::step_crowds(in, 1, in[0].size(), crowd, crowd_f);
    CHECK(c.count() == 0);
  }
  for (int u = 0; u < n; ++u) CHECK(crowd[u].has_output());
}
