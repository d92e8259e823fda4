// Validation clips dumped by `python3 -m weights_tool.n3p evaluate ... --dump-direct FILE`
// (examples/weights/N3P_README.md): per clip, 30 Hz arrays "p" (3 trackers x xyz, metres) and "q6"
// (3 trackers x the pipeline's 6D layout: forward (Z) then up (Y) axis), plus ground-truth joints.
// Read by the C++ evaluations (tests/n3p/eval_direct.cpp, examples/n3p_physics_eval.cpp).
#pragma once
#include <nlohmann/json.hpp>

#include "sparsebody/pose/rotation6d.hpp"
#include "sparsebody/trackers/types.hpp"

namespace sparsebody::recordings {

// Frame t of a dumped clip as tracker input (headset and both controllers valid, no pelvis).
inline trackers::TrackerFrame n3p_dump_frame(const nlohmann::json& clip, int t) {
  trackers::TrackerFrame f;
  f.time = t / 30.0;
  const auto& p3 = clip["p"][t];
  const auto& q = clip["q6"][t];
  for (int k = 0; k < 3; ++k) {
    double d6[6];
    for (int i = 0; i < 6; ++i) d6[i] = q[6 * k + i];
    const Eigen::Matrix3d R = pose::from6d(d6);
    f.pose[k].position = trackers::to_xr(Eigen::Vector3d(p3[3 * k], p3[3 * k + 1], p3[3 * k + 2]));
    f.pose[k].orientation = trackers::to_xr(Eigen::Quaterniond(R));
    f.valid[k] = true;
  }
  return f;
}

}  // namespace sparsebody::recordings
