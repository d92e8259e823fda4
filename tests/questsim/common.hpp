// Shared helpers of the QuestSim tests: the generated random-weight policy, a synthetic user stream.
#pragma once
#include <doctest/doctest.h>

#include <cmath>
#include <cstdlib>
#include <string>

#include "sparsebody/avatar/questsim.hpp"

namespace questsim_test {

using namespace sparsebody;

// Written by the CTest fixture questsim_policy_generate (weights_tool.questsim policy).
inline std::string policy_path() {
  const char* p = std::getenv("SPARSEBODY_QUESTSIM_POLICY");
  REQUIRE_MESSAGE(p != nullptr, "SPARSEBODY_QUESTSIM_POLICY not set (run through ctest)");
  return p;
}

template <class C>
inline std::shared_ptr<const typename C::Weights> policy_weights() {
  static auto w = C::load_weights(policy_path());
  return w;
}

inline trackers::Quatf yaw_pitch(double yaw, double pitch) {
  const Eigen::Quaterniond q = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitX());
  return trackers::to_xr(q);
}

// A user of `height` standing at (x0, z0), facing -Z (OpenXR forward), swaying, turning slowly and
// waving the controllers. Head and both hands valid, no pelvis tracker.
inline trackers::TrackerFrame user_frame(double t, double height = 1.62, double x0 = 0.3, double z0 = -0.4) {
  trackers::TrackerFrame f;
  f.time = t;
  const double yaw = 0.4 * std::sin(0.3 * t);
  const Eigen::Matrix3d Ry = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Vector3d head(x0 + 0.05 * std::sin(1.1 * t), 0.936 * height + 0.01 * std::sin(2.3 * t), z0 + 0.03 * std::sin(0.7 * t));
  f.pose[0] = {yaw_pitch(yaw, 0.1 * std::sin(0.9 * t)), trackers::to_xr(head)};
  for (int side = 0; side < 2; ++side) {
    const double sx = side == 0 ? -1.0 : 1.0;  // OpenXR: +X is the user's right
    const Eigen::Vector3d local(sx * 0.22, -0.45 + 0.15 * std::sin(1.7 * t + side), -0.25 + 0.1 * std::sin(1.3 * t));
    f.pose[1 + side] = {yaw_pitch(yaw + sx * 0.2, 0.3 * std::sin(t)), trackers::to_xr(head + Ry * (local * height / 1.62))};
  }
  f.valid = {true, true, true, false};
  return f;
}

template <class Sim>
inline bool state_finite(const Sim& sim) {
  bool ok = sim.q().allFinite() && sim.v().allFinite();
  for (int i = 0; i < sim.model().nb; ++i) ok = ok && sim.data().p[i].allFinite() && sim.data().R[i].allFinite();
  return ok;
}

}  // namespace questsim_test
