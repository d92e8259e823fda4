// Shared helpers of the Neural3Points tests.
#pragma once
#include <cmath>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "sparsebody/predict/n3p_predictor.hpp"

namespace n3p_test {

inline std::string golden_dir() { return SPARSEBODY_N3P_GOLDEN_DIR; }
inline std::string small_prefix() { return golden_dir() + "/n3p_small"; }

inline nlohmann::json read_json(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw std::runtime_error("cannot open " + path);
  return nlohmann::json::parse(f);
}

// The random small predictor of the golden (hidden 16, 24, 24).
using SmallPredictor = sparsebody::predict::N3PPredictor<float, 16, 24, 24>;

// Tracker set of golden frame t.
inline sparsebody::features::n3p::TrackerSet golden_trackers(const nlohmann::json& g, int t) {
  sparsebody::features::n3p::TrackerSet o;
  const auto& p = g["trackers_p"][t];
  const auto& q = g["trackers_q6"][t];
  for (int k = 0; k < 3; ++k) {
    o[k].p = Eigen::Vector3d(p[3 * k], p[3 * k + 1], p[3 * k + 2]);
    o[k].fwd = Eigen::Vector3d(q[6 * k], q[6 * k + 1], q[6 * k + 2]);
    o[k].up = Eigen::Vector3d(q[6 * k + 3], q[6 * k + 4], q[6 * k + 5]);
  }
  return o;
}

}  // namespace n3p_test

#include "sparsebody/avatar/n3p_direct.hpp"
#include "sparsebody/trackers/types.hpp"

namespace n3p_test {

using SmallPipeline = sparsebody::avatar::N3PPipeline<float, 16, 24, 24>;

// Golden frame t as an OpenXR-style tracker frame at 30 Hz (pelvis absent); validity from "present".
inline sparsebody::trackers::TrackerFrame golden_frame(const nlohmann::json& g, int t) {
  using namespace sparsebody;
  const auto o = golden_trackers(g, t);
  trackers::TrackerFrame f;
  f.time = t / 30.0;
  for (int k = 0; k < 3; ++k) {
    Eigen::Matrix3d R;
    R.col(2) = o[k].fwd.normalized();
    R.col(0) = o[k].up.cross(R.col(2)).normalized();
    R.col(1) = R.col(2).cross(R.col(0));
    f.pose[k].position = trackers::to_xr(o[k].p);
    f.pose[k].orientation = trackers::to_xr(Eigen::Quaterniond(R));
    f.valid[k] = g["present"][t][k].get<int>() != 0;
  }
  f.valid[3] = false;
  return f;
}

}  // namespace n3p_test
