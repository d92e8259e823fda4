// The C++ pipeline equals the Python reference pipeline (weights_tool/lobstr/reference.py) on a
// CMU clip: tracker synthesis, features, network outputs in streaming and window modes (<= 1e-4).
#include <doctest/doctest.h>

#include <cmath>

#include "common.hpp"
#include "sparsebody/recordings/bvh.hpp"
#include "sparsebody/recordings/tracker_synthesis.hpp"

using namespace sparsebody;
using pipeline_test::golden;

namespace {
double max_abs_diff(const float* a, const nlohmann::json& b, int n) {
  double m = 0;
  for (int i = 0; i < n; ++i) m = std::max(m, std::abs(static_cast<double>(a[i]) - b[i].get<double>()));
  return m;
}
}  // namespace

TEST_CASE("pipeline parity with the PyTorch reference: features and outputs, streaming and window") {
  const auto g = pipeline_test::read_json(golden("lobstr_pipeline_small.golden.json"));
  const auto frames = pipeline_test::golden_frames(g);
  REQUIRE(frames.size() > 60);
  for (auto mode : {avatar::RunMode::Streaming, avatar::RunMode::Window}) {
    avatar::LoBSTrConfig cfg;
    cfg.mode = mode;
    pipeline_test::SmallPipeline p(pipeline_test::small_weights(), cfg);
    features::Calibration c;
    c.scale = g["scale"].get<double>();
    p.set_calibration(c);
    const auto& expect = g[mode == avatar::RunMode::Streaming ? "outputs" : "window_outputs"];
    double worst_x = 0, worst_y = 0;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      CHECK(p.push(frames[i]) == 1);  // 30 Hz input: one model step per frame
      REQUIRE(p.has_output());
      worst_x = std::max(worst_x, max_abs_diff(p.features(), g["features"][i], 37));
      worst_y = std::max(worst_y, max_abs_diff(p.network_output(), expect[i], 52));
    }
    INFO("mode " << (mode == avatar::RunMode::Streaming ? "streaming" : "window"));
    CHECK(worst_x <= 1e-4);
    CHECK(worst_y <= 1e-4);
    // the outputs really change over the clip (the comparison is not against a constant)
    double spread = 0;
    for (std::size_t i = 1; i < frames.size(); ++i)
      spread = std::max(spread, std::abs(expect[i][0].get<double>() - expect[0][0].get<double>()));
    CHECK(spread > 1e-3);
  }
}

TEST_CASE("tracker synthesis from a BVH equals the Python synthesis") {
  const auto g = pipeline_test::read_json(golden("lobstr_pipeline_small.golden.json"));
  const std::string path = "/usr/share/assimp/models/BVH/" + g["clip"].get<std::string>();
  std::ifstream probe(path);
  if (!probe) {
    MESSAGE("skipped: " << path << " not installed (Debian package assimp-testmodels)");
    return;
  }
  const recordings::BvhClip clip = recordings::read_bvh(path);
  const auto map = pose::JointMap::from_names(clip.skeleton, path);
  const auto syn = recordings::synthesize_trackers(clip, map, recordings::guess_units(clip.skeleton, map));
  const auto& idx = g["clip_frames"];
  double worst_p = 0, worst_q = 0;
  for (std::size_t i = 0; i < idx.size(); ++i) {
    const auto& f = syn.frames[idx[i].get<std::size_t>()];
    for (int k = 0; k < 4; ++k) {
      const auto& P = g["positions"][i][k];
      const auto& Q = g["quaternions_xyzw"][i][k];
      worst_p = std::max({worst_p, std::abs(f.pose[k].position.x - P[0].get<double>()),
                          std::abs(f.pose[k].position.y - P[1].get<double>()), std::abs(f.pose[k].position.z - P[2].get<double>())});
      const double dot = f.pose[k].orientation.x * Q[0].get<double>() + f.pose[k].orientation.y * Q[1].get<double>() +
                         f.pose[k].orientation.z * Q[2].get<double>() + f.pose[k].orientation.w * Q[3].get<double>();
      worst_q = std::max(worst_q, 1.0 - std::abs(dot));
    }
  }
  CHECK(worst_p <= 1e-4);
  CHECK(worst_q <= 1e-6);
}

TEST_CASE("resampling: 120 Hz input gives the 30 Hz model frames") {
  const auto g = pipeline_test::read_json(golden("lobstr_pipeline_small.golden.json"));
  const auto frames = pipeline_test::golden_frames(g);
  pipeline_test::SmallPipeline a(pipeline_test::small_weights()), b(pipeline_test::small_weights());
  features::Calibration c;
  c.scale = g["scale"].get<double>();
  a.set_calibration(c);
  b.set_calibration(c);
  int steps = 0;
  double worst = 0;
  for (std::size_t i = 0; i + 1 < frames.size(); ++i) {
    a.push(frames[i]);
    // four 120 Hz frames per 30 Hz frame, interpolated between the golden frames
    for (int s = 0; s < 4; ++s) {
      trackers::TrackerFrame f = frames[i];
      const double t = s / 4.0;
      f.time = (i + t) / 30.0;
      for (int k = 0; k < 4; ++k) {
        const auto p0 = trackers::to_eigen(frames[i].pose[k].position), p1 = trackers::to_eigen(frames[i + 1].pose[k].position);
        f.pose[k].position = trackers::to_xr(Eigen::Vector3d((1 - t) * p0 + t * p1));
        f.pose[k].orientation = trackers::to_xr(trackers::to_eigen(frames[i].pose[k].orientation).slerp(t, trackers::to_eigen(frames[i + 1].pose[k].orientation)));
      }
      steps += b.push(f);
    }
    if (i > 0) worst = std::max(worst, max_abs_diff(a.network_output(), nlohmann::json(std::vector<double>(b.network_output(), b.network_output() + 52)), 52));
  }
  CHECK(steps == static_cast<int>(frames.size()) - 1);
  CHECK(worst < 1e-3);
}
