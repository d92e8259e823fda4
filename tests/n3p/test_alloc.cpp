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

// Toe pins while the user stands (N3PConfig::Pin::Toe, pose/foot_roll.hpp): the headset drifts
// forwards 10 cm at 4 cm/s (still by trackers::Stillness) and the hips follow it, so a planted rear
// foot's ankle leaves the leg's reach and the foot rolls over its toe. That branch allocates nothing
// either. The test checks that it ran: the foot turned while its toe stayed, and without the roll
// (max_foot_roll = 0) the toe slides. A foot rolled to the 80 deg limit (the ankle right above the
// toe: how far that is depends on the stance the weights stopped in) slides with the hips from there
// on, as smoothly as they move: no frame moves it further than the headset's drift.
TEST_CASE("n3p pipeline: no allocation per frame while a standing foot rolls over its pinned toe, shipped weights") {
  using sparsebody_test::Phase;
  auto frames = sparsebody_test::session({{Phase::Walk, 2.0, 1.62}, {Phase::Stand, 4.0, 1.62}}, 72.0, 0.3, false);
  const Eigen::Vector3d fwd = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY())) * Eigen::Vector3d(0, 0, -1);
  const double drift_speed = 0.04;  // m/s
  for (auto& f : frames) {
    const double s = drift_speed * std::clamp(f.time - 3.0, 0.0, 2.5);  // m forwards, t = 3-5.5 s
    for (auto& pose : f.pose) {
      pose.position.x += static_cast<float>(s * fwd.x());
      pose.position.z += static_cast<float>(s * fwd.z());
    }
  }
  const auto w = avatar::N3PDirect::load(std::string(SPARSEBODY_SOURCE_DIR) + "/examples/weights/n3p");
  struct Outcome {
    double turned = 0;       // rad, the most a foot turned from its planted orientation
    double toe_moved = 0;    // m, the most a toe moved while its foot was below the roll's limit
    double toe_step = 0;     // m, the most a toe moved in one output frame
    double at_limit = 0;     // s, how long a foot spent at the roll's limit
    long long allocations = 0;
  };
  auto run = [&](double max_roll) {
    avatar::N3PConfig c;
    c.max_foot_roll = max_roll;
    avatar::N3PDirect p(w, c);
    REQUIRE(p.config().pin == avatar::N3PConfig::Pin::Toe);
    const int toe[2] = {p.joint_map()[pose::Role::ToeL], p.joint_map()[pose::Role::ToeR]};
    const int foot[2] = {p.joint_map()[pose::Role::FootL], p.joint_map()[pose::Role::FootR]};
    for (int i = 0; i < 3; ++i) p.push(frames[static_cast<std::size_t>(i)]);
    Eigen::Quaterniond planted[2];
    Eigen::Vector3d toe_at[2], toe_last[2];
    bool limited[2] = {false, false};
    Outcome o;
    {
      sparsebody_test::AllocationCounter counter;
      for (std::size_t i = 3; i < frames.size(); ++i) {
        if (p.push(frames[i]) == 0 || !p.has_output()) continue;
        for (int k = 0; k < 2; ++k) {
          const Eigen::Quaterniond q = p.world().rotation[foot[k]];
          const Eigen::Vector3d x = p.world().position[toe[k]] * p.user_scale();
          const Eigen::Vector3d e = p.world().position[foot[k]] - p.world().position[toe[k]];  // toe -> ankle
          if (frames[i].time < 2.9) {  // standing since t = 2 s, before the drift
            planted[k] = q;
            toe_at[k] = toe_last[k] = x;
            continue;
          }
          o.turned = std::max(o.turned, planted[k].angularDistance(q));
          limited[k] = limited[k] || std::asin(e.y() / e.norm()) > 79.9 * M_PI / 180;
          if (limited[k]) o.at_limit += 0.5 / p.meta().frame_rate;
          if (!limited[k]) o.toe_moved = std::max(o.toe_moved, std::hypot(x.x() - toe_at[k].x(), x.z() - toe_at[k].z()));
          o.toe_step = std::max(o.toe_step, std::hypot(x.x() - toe_last[k].x(), x.z() - toe_last[k].z()));
          toe_last[k] = x;
        }
      }
      o.allocations = counter.count();
    }
    return o;
  };
  const Outcome rolled = run(avatar::N3PConfig{}.max_foot_roll), fixed = run(0.0);
  MESSAGE("standing, headset 10 cm forwards at 4 cm/s: feet turned up to " << rolled.turned * 180 / M_PI << " deg, toes moved up to "
                                                                           << 100 * rolled.toe_moved << " cm below the roll's limit ("
                                                                           << rolled.at_limit << " s at it; largest step "
                                                                           << 100 * rolled.toe_step << " cm); without the roll: "
                                                                           << fixed.turned * 180 / M_PI << " deg, largest step "
                                                                           << 100 * fixed.toe_step << " cm");
  CHECK(rolled.allocations == 0);
  CHECK(fixed.allocations == 0);
  CHECK(rolled.turned > 0.05);        // the roll ran (about 3 deg or more) ...
  CHECK(rolled.toe_moved < 1e-5);     // ... about the pinned toe
  CHECK(rolled.at_limit < 1.0);       // most of the 2.5 s drift was absorbed by the roll
  // at the limit the toe slides with the hips, no faster than the headset drifts (a frame's 1.3 mm;
  // a lock released or slid at once would jump by centimetres)
  CHECK(rolled.toe_step < 2 * drift_speed / avatar::N3PDirect(w).meta().frame_rate);
  CHECK(fixed.toe_step > 0.0002);     // without the roll the hip drags the toe
}

// Held feet on a platform (N3PConfig::platform_height): the user walks up a 0.4 m ramp and stands;
// the feet pinned on the ramp rise with the head while the user stands. That branch, and the heel
// settling of the feet held at the stop, allocate nothing. The test checks that the rise ran: the
// toes end on the platform and the head on the headset (with the rise off, the shipped weights left
// the head 10.6 cm below it, the toes 33 cm up).
TEST_CASE("n3p pipeline: no allocation per frame while held feet rise onto a platform, shipped weights") {
  using sparsebody_test::Phase;
  auto frames = sparsebody_test::session({{Phase::Stand, 2.0, 1.62}, {Phase::Walk, 2.0, 1.62}, {Phase::Stand, 3.0, 1.62}}, 72.0, 0.3, false);
  for (auto& f : frames) {
    const double d = 0.4 * std::clamp((f.time - 2.0) / 2.0, 0.0, 1.0);
    for (auto& pose : f.pose) pose.position.y += static_cast<float>(d);
  }
  avatar::N3PDirect p(avatar::N3PDirect::load(std::string(SPARSEBODY_SOURCE_DIR) + "/examples/weights/n3p"));
  REQUIRE(p.calibrate(frames.front()));
  const int toe[2] = {p.joint_map()[pose::Role::ToeL], p.joint_map()[pose::Role::ToeR]};
  const int head = p.joint_map()[pose::Role::Head];
  for (int i = 0; i < 3; ++i) p.push(frames[static_cast<std::size_t>(i)]);
  double lowest_toe = 1e9, head_err = 0;
  int n = 0;
  long long allocations = 0;
  {
    sparsebody_test::AllocationCounter counter;
    for (std::size_t i = 3; i < frames.size(); ++i) {
      if (p.push(frames[i]) == 0 || !p.has_output() || frames[i].time < 6.0) continue;
      for (int k = 0; k < 2; ++k) lowest_toe = std::min(lowest_toe, p.world().position[toe[k]].y() * p.user_scale());
      head_err += std::abs(p.world().position[head].y() - p.trackers()[0].p.y()) * p.user_scale();
      ++n;
    }
    allocations = counter.count();
  }
  REQUIRE(n > 20);
  MESSAGE("on the platform: lowest toe " << 100 * lowest_toe << " cm, head " << 100 * head_err / n << " cm from the headset");
  CHECK(allocations == 0);
  CHECK(lowest_toe > 0.35);
  CHECK(head_err / n < 0.03);
}
