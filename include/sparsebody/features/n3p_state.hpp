// Neural3Points character state layouts (SCA 2022, §4), all quantities in a heading frame h
// (features/heading_frame.hpp); rotations as 6D, columns [2, 1] of R (pose/rotation6d.hpp).
//
//   o     tracker input, X in {H, L, R}: [p_H p_L p_R (9) | q6_H q6_L q6_R (18)]               27
//   z     aggregated upper-body state: [p_up (3) | v_up (3) | L_up (3) | dh = (dx, dz, dtheta)]  12
//         (centroid, its velocity, angular momentum; dh relative to the previous heading frame)
//   g_lo  [p_j (27) | v_j (27) | q6_j (54), j in J_lo | c_L c_R (2) | z (12)]                   122
//   g_up  [p_j (36) | v_j (36) | q6_j (72), j in J_up]                                           144
//
// Sub-predictor inputs and outputs (Eq. (2)):
//   G_sig: inv(h^{t-1}) (x) o^t                    -> z~^t                                27 -> 12
//   G_lo : [z~^t | g_lo^{t-1}]                     -> [g_lo^t | z*^{t+1}]                134 -> 134
//   G_up : [inv(h^t) (x) o^t | g_up^{t-1}]         -> [g_up^t | o*^{t+1}]                171 -> 171
// Python twin: weights_tool/n3p/layout.py.
#pragma once

namespace sparsebody::features::n3p {

inline constexpr int kTrackers = 3;     // H, L, R
inline constexpr int kLowerJoints = 9;  // J_lo
inline constexpr int kUpperJoints = 12; // J_up

// Joint sets on the standard skeleton (names as in the weights file's meta.skeleton).
inline constexpr const char* kLowerNames[kLowerJoints] = {"Hips",     "UpperLeg_L", "LowerLeg_L", "Foot_L", "Toes_L",
                                                          "UpperLeg_R", "LowerLeg_R", "Foot_R", "Toes_R"};
inline constexpr const char* kUpperNames[kUpperJoints] = {"Spine",      "Chest",      "Neck",       "Head",
                                                          "Shoulder_L", "UpperArm_L", "LowerArm_L", "Hand_L",
                                                          "Shoulder_R", "UpperArm_R", "LowerArm_R", "Hand_R"};
inline constexpr const char* kTrackerJointNames[kTrackers] = {"Head", "Hand_L", "Hand_R"};

// o
inline constexpr int kO = 9 + 6 * kTrackers;  // 27
inline constexpr int kOPos = 0, kORot = 9;
// z
inline constexpr int kZ = 12;
inline constexpr int kZCentroid = 0, kZVelocity = 3, kZMomentum = 6, kZDelta = 9;

// A joint-state block of k joints: [p (3k) | v (3k) | q6 (6k)].
template <int K>
struct JointBlock {
  static constexpr int size = 12 * K;
  static constexpr int pos(int j) { return 3 * j; }
  static constexpr int vel(int j) { return 3 * K + 3 * j; }
  static constexpr int rot(int j) { return 6 * K + 6 * j; }
};
using LowerBlock = JointBlock<kLowerJoints>;
using UpperBlock = JointBlock<kUpperJoints>;

// g_lo
inline constexpr int kGloContact = LowerBlock::size;  // c_L, c_R
inline constexpr int kGloZ = kGloContact + 2;          // z inside g_lo
inline constexpr int kGloDelta = kGloZ + kZDelta;      // dh inside g_lo
inline constexpr int kGlo = kGloZ + kZ;                // 122
// g_up
inline constexpr int kGup = UpperBlock::size;          // 144

// Network sizes.
inline constexpr int kSigIn = kO, kSigOut = kZ;                    // 27 -> 12
inline constexpr int kLoIn = kZ + kGlo, kLoOut = kGlo + kZ;        // 134 -> 134
inline constexpr int kUpIn = kO + kGup, kUpOut = kGup + kO;        // 171 -> 171

}  // namespace sparsebody::features::n3p
