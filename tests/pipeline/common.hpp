// Shared helpers for the pipeline tests.
#pragma once
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "sparsebody/avatar/lobstr_pipeline.hpp"

namespace pipeline_test {

inline std::string golden(const std::string& name) { return std::string(SPARSEBODY_PIPELINE_GOLDEN_DIR) + "/" + name; }

inline nlohmann::json read_json(const std::string& path) {
  std::ifstream f(path);
  return nlohmann::json::parse(f);
}

using SmallPipeline = sparsebody::avatar::LoBSTrPipeline<float, 32, 16>;

inline std::shared_ptr<const SmallPipeline::Weights> small_weights() {
  static auto w = SmallPipeline::load(golden("lobstr_pipeline_small.weights.json"));
  return w;
}

// Golden tracker frames (30 Hz) as the C++ API receives them.
inline std::vector<sparsebody::trackers::TrackerFrame> golden_frames(const nlohmann::json& g) {
  std::vector<sparsebody::trackers::TrackerFrame> out;
  const auto& P = g["positions"];
  const auto& Q = g["quaternions_xyzw"];
  for (std::size_t i = 0; i < P.size(); ++i) {
    sparsebody::trackers::TrackerFrame f;
    f.time = static_cast<double>(i) / 30.0;
    for (int k = 0; k < 4; ++k) {
      f.pose[k].position = {P[i][k][0].get<float>(), P[i][k][1].get<float>(), P[i][k][2].get<float>()};
      f.pose[k].orientation = {Q[i][k][0].get<float>(), Q[i][k][1].get<float>(), Q[i][k][2].get<float>(), Q[i][k][3].get<float>()};
      f.valid[k] = true;
    }
    out.push_back(f);
  }
  return out;
}

}  // namespace pipeline_test
