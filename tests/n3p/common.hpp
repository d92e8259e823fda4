// Shared helpers of the Neural3Points tests.
#pragma once
#include <cmath>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "sparsebody/avatar/n3p_predictor.hpp"

namespace n3p_test {

inline std::string golden_dir() { return SPARSEBODY_N3P_GOLDEN_DIR; }
inline std::string small_prefix() { return golden_dir() + "/n3p_small"; }

inline nlohmann::json read_json(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw std::runtime_error("cannot open " + path);
  return nlohmann::json::parse(f);
}

// The random small predictor of the golden (hidden 16, 24, 24).
using SmallPredictor = sparsebody::avatar::N3PPredictor<float, 16, 24, 24>;

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
