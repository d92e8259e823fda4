// Shared helpers of the Neural3Points physics-mode tests: synthetic users (no data files needed
// besides the default weights).
#pragma once
#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "sparsebody/avatar/n3p_physics.hpp"

namespace n3p_physics_test {

using Physics = sparsebody::avatar::N3PPhysicsDefault;

inline const Physics::Weights& weights() {
  static const Physics::Weights w = Physics::load(SPARSEBODY_N3P_WEIGHTS);
  return w;
}

// A user of the standard skeleton's size (head joint 1.378 m) at 30 Hz. speed 0: standing still, hands at the hips, a slight sway; speed > 0:
// walking a circle of radius 1.5 m at `speed` m/s, facing along the path, hands swinging.
inline sparsebody::trackers::TrackerFrame user_frame(int t, double speed) {
  using namespace sparsebody;
  const double T = t / 30.0, r = 1.5;
  const double a = speed * T / r, s = std::sin(2 * M_PI * 0.9 * T);
  trackers::TrackerFrame f;
  f.time = T;
  const Eigen::Vector3d c(r * std::sin(a), 0, r * std::cos(a));
  const Eigen::Quaterniond yaw(Eigen::AngleAxisd(a + M_PI / 2, Eigen::Vector3d::UnitY()));
  const double sway = speed > 0 ? 0.15 * s : 0.01 * s;
  const Eigen::Vector3d pos[3] = {c + Eigen::Vector3d(0, 1.378 + 0.01 * s, 0),
                                  c + yaw * Eigen::Vector3d(0.2, 0.8, sway),
                                  c + yaw * Eigen::Vector3d(-0.2, 0.8, -sway)};
  for (int k = 0; k < 3; ++k) {
    f.pose[k].position = trackers::to_xr(pos[k]);
    f.pose[k].orientation = trackers::to_xr(yaw);
    f.valid[k] = true;
  }
  return f;
}

// The pipeline's output pose (local rotations, root, world positions) is finite.
template <class P>
bool finite_output(const P& p) {
  bool ok = p.pose().root_position.allFinite();
  for (std::size_t j = 0; j < p.pose().local.size(); ++j)
    ok &= p.pose().local[j].coeffs().allFinite() && p.world().position[j].allFinite();
  return ok;
}

// A correction policy (kind "n3p_correction_policy", 1008-256-256-48 tanh) written to `path`: every
// weight zero and every output bias `bias` (so each output is tanh(bias)), meta.action_scale `scale`
// (omitted when negative). A test double of what weights_tool.questsim.train --task n3p exports.
inline std::string write_correction_policy(const std::string& path, double bias, double scale) {
  const int sizes[4] = {1008, 256, 256, 48};
  nlohmann::json d;
  d["format"] = "sparsebody-weights";
  d["version"] = 1;
  d["kind"] = "n3p_correction_policy";
  d["meta"] = {{"input_size", 1008}, {"output_size", 48}, {"frame_rate", 30}};
  if (scale >= 0) d["meta"]["action_scale"] = scale;
  for (int l = 0; l < 3; ++l) {
    const std::string n = "layers." + std::to_string(l);
    d["tensors"][n + ".weight"] = {{"shape", {sizes[l + 1], sizes[l]}},
                                   {"data", std::vector<double>(std::size_t(sizes[l + 1]) * sizes[l], 0.0)}};
    d["tensors"][n + ".bias"] = {{"shape", {sizes[l + 1]}}, {"data", std::vector<double>(sizes[l + 1], l == 2 ? bias : 0.0)}};
  }
  std::ofstream(path) << d.dump();
  return path;
}

}  // namespace n3p_physics_test
