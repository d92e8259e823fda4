// Shared by the training-environment tests: the Neural3Points standard skeleton's meta (from the
// shipped lower-body weights) and a synthetic clip of it.
#pragma once
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <doctest/doctest.h>

#include "sparsebody/control/n3p_sim_retarget.hpp"
#include "sparsebody/predict/n3p_predictor.hpp"
#include "sparsebody/recordings/bvh.hpp"

namespace training_test {

using namespace sparsebody;

inline const predict::N3PMeta& meta() {
  static const predict::N3PMeta m = [] {
    using Lo = predict::N3PPredictor<float>::LoNet;
    return predict::N3PMeta::from(
        nn::NetworkWeights<Lo>::load(std::string(SPARSEBODY_SOURCE_DIR) + "/examples/weights/n3p_lower.json",
                                     networks::kN3PLowerKind)->info());
  }();
  return m;
}

// 4 s at 30 fps of the standard skeleton standing (the Neural3Points standing pose: its joint
// frames are the capture's, bones along local X, so the rest pose is not upright), both arms swinging
// about their local Z axis, written as a BVH would be (ZXY Euler channels, root in metres).
inline recordings::BvhClip synthetic_clip() {
  recordings::BvhClip c;
  c.skeleton = meta().skeleton;
  const int n = c.skeleton.size();
  c.end_site.assign(n, 0);
  c.end_offset.assign(n, Eigen::Vector3d::Zero());
  using Ch = recordings::BvhChannel;
  for (int j = 0; j < n; ++j) {
    if (j == 0) c.channels.push_back({Ch::Xposition, Ch::Yposition, Ch::Zposition, Ch::Zrotation, Ch::Xrotation, Ch::Yrotation});
    else c.channels.push_back({Ch::Zrotation, Ch::Xrotation, Ch::Yrotation});
    c.channel_count += static_cast<int>(c.channels.back().size());
  }
  c.frame_time = 1.0 / 30;
  c.frames = 120;
  const auto W = control::N3PSimRetarget<double, 24, 72>::neutral_rotations(meta());
  const int sl = c.skeleton.find("UpperArm_L"), sr = c.skeleton.find("UpperArm_R");
  REQUIRE(sl > 0);
  REQUIRE(sr > 0);
  for (int f = 0; f < c.frames; ++f) {
    std::vector<double> row;
    const double a = 0.5 * std::sin(2 * M_PI * f / 60.0);
    for (int j = 0; j < n; ++j) {
      const int p = c.skeleton.parents[j];
      Eigen::Matrix3d L = p < 0 ? W[j] : Eigen::Matrix3d(W[p].transpose() * W[j]);
      if (j == sl || j == sr) L = L * Eigen::AngleAxisd(j == sl ? a : -a, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      if (p < 0) row.insert(row.end(), {0.0, meta().standing_hips_height, 0.002 * f});  // creeping forwards
      const Eigen::Vector3d e = L.eulerAngles(2, 0, 1) * (180.0 / M_PI);  // L = Rz Rx Ry
      row.insert(row.end(), {e(0), e(1), e(2)});
    }
    c.motion.insert(c.motion.end(), row.begin(), row.end());
  }
  return c;
}

// n x A actions drawn from N(0, scale^2), row-major, from a seeded stream.
template <int A>
std::vector<float> random_actions(int n, unsigned seed, float scale) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> g(0.f, scale);
  std::vector<float> a(static_cast<std::size_t>(n) * A);
  for (float& x : a) x = g(rng);
  return a;
}

}  // namespace training_test
