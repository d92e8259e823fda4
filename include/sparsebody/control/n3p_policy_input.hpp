// Neural3Points control-policy input s = {x_t, g_t+1, g_t+2, g_t+3} (SCA 2022, §5), all in the
// reference heading frame h_ref (the predictor's heading at the simulation time: "we convert x_t
// into a reference global heading frame ... {g_t+k} are expressed in the same heading frame").
// Each block covers the 21 joints of the standard skeleton (its order) like g_lo / g_up do:
// [p_0 .. p_20 (63) | v_0 .. v_20 (63) | q6_0 .. q6_20 (126)]:
//
//   x_t      the simulated character: joint positions, linear velocities, world rotations (6D =
//            columns [2, 1] of R_y(-theta_ref) R_j) in h_ref                           21 x 12 = 252
//   g_t+k    the predicted state g^{t+k} = {g_lo, g_up} (features/n3p_state.hpp, in its own
//            heading h^{t+k}), re-expressed in h_ref: points inv(h_ref) (x) h^{t+k} (x) p, vectors
//            and both 6D columns rotated by R_y(theta_k - theta_ref) (kept as predicted, not
//            re-orthonormalised, like o* in features/n3p_tracker_input.hpp)      252 each
//   s = [x_t | g_t+1 | g_t+2 | g_t+3]                                                    1008
// Contacts and z of g_lo are not part of s (the paper lists joint states only).
// Policy output u (kPolicyOut): the 6D (columns [2, 1]) of the target local rotation of every
// internal joint j = 1..20 of the skeleton, in skeleton order (control/n3p_control_predictor.hpp
// turns it into PD targets through control/n3p_sim_retarget.hpp).
// Python twin: weights_tool/n3p_physics/policy_input.py (parity-tested, tests/n3p_physics).
#pragma once
#include <array>

#include <Eigen/Core>

#include "sparsebody/features/heading_frame.hpp"
#include "sparsebody/features/n3p_state.hpp"
#include "sparsebody/pose/rotation6d.hpp"

namespace sparsebody::control::n3p_policy {

namespace n3p = features::n3p;
inline constexpr int kJoints = n3p::kLowerJoints + n3p::kUpperJoints;  // 21
inline constexpr int kBlock = 12 * kJoints;                             // 252
inline constexpr int kFuture = 3;                                       // g_t+1 .. g_t+3
inline constexpr int kPolicyIn = kBlock * (1 + kFuture);                // 1008
inline constexpr int kPolicyOut = 6 * (kJoints - 1);                    // 120

// One joint's block from world quantities.
template <typename T>
inline void joint_block(const features::HeadingFrame& h, const Eigen::Vector3d& p, const Eigen::Vector3d& v,
                        const Eigen::Vector3d& fwd, const Eigen::Vector3d& up, T* out, int j) noexcept {
  const Eigen::Vector3d a = h.point_to_local(p), b = h.vector_to_local(v), c = h.vector_to_local(fwd), d = h.vector_to_local(up);
  for (int i = 0; i < 3; ++i) {
    out[3 * j + i] = static_cast<T>(a[i]);
    out[3 * kJoints + 3 * j + i] = static_cast<T>(b[i]);
    out[6 * kJoints + 6 * j + i] = static_cast<T>(c[i]);
    out[6 * kJoints + 6 * j + 3 + i] = static_cast<T>(d[i]);
  }
}

// x_t from the simulated character's joints (world: positions, velocities, rotations), skeleton order.
template <typename T>
inline void character_block(const features::HeadingFrame& href, const Eigen::Vector3d* p, const Eigen::Vector3d* v,
                            const Eigen::Matrix3d* R, T* out) noexcept {
  for (int j = 0; j < kJoints; ++j) joint_block(href, p[j], v[j], Eigen::Vector3d(R[j].col(2)), Eigen::Vector3d(R[j].col(1)), out, j);
}

// g_t+k from a predicted state in heading hk; lower / upper: skeleton index of J_lo[i] / J_up[i].
template <typename T, typename G>
inline void predicted_block(const features::HeadingFrame& href, const features::HeadingFrame& hk, const G* glo,
                            const G* gup, const int* lower, const int* upper, T* out) noexcept {
  auto put = [&](const G* g, int K, int i, int j) {
    const G* p = g + 3 * i;
    const G* v = g + 3 * K + 3 * i;
    const G* q = g + 6 * K + 6 * i;
    joint_block(href, hk.point_to_world(Eigen::Vector3d(p[0], p[1], p[2])), hk.vector_to_world(Eigen::Vector3d(v[0], v[1], v[2])),
                hk.vector_to_world(Eigen::Vector3d(q[0], q[1], q[2])), hk.vector_to_world(Eigen::Vector3d(q[3], q[4], q[5])), out, j);
  };
  for (int i = 0; i < n3p::kLowerJoints; ++i) put(glo, n3p::kLowerJoints, i, lower[i]);
  for (int i = 0; i < n3p::kUpperJoints; ++i) put(gup, n3p::kUpperJoints, i, upper[i]);
}

// Policy output -> local rotation of internal joint j (1..20), orthonormalised (pose::from6d).
template <typename T>
inline Eigen::Matrix3d target_rotation(const T* u, int j) noexcept {
  return pose::from6d(u + 6 * (j - 1));
}

}  // namespace sparsebody::control::n3p_policy
