// Control policies as MLPs, tensors under "layers.<i>." (reference: weights_tool/nets.py MLPPolicy).
//  - Neural3Points control policy pi (SCA 2022, §5): four fully connected layers of neurons, i.e.
//    input -> 256 -> 256 -> output with ReLU on the two hidden layers; the output is the PD target
//    rotations of the internal joints.
//  - Neural3Points correction policy (issue 14 item 4, control/n3p_target_correction.hpp): the same
//    input s, [256, 256] tanh, tanh output in [-1, 1]: a correction of each PD target (rad / scale).
//  - QuestSim policy (SIGGRAPH Asia 2022, Appendix): hidden layers [400, 300, 200], tanh on every
//    layer including the output, which is in [-1, 1] and scaled to +/-200 Nm by the caller.
#pragma once
#include "sparsebody/nn/activation.hpp"
#include "sparsebody/nn/compose.hpp"
#include "sparsebody/nn/mlp.hpp"

namespace sparsebody::networks {

namespace policy_names {
inline constexpr char kLayers[] = "layers";
}

// W: stored weight type (T, or nn::f16 to halve the bytes per step).
template <typename T, int In, int Out, int Hidden = 256, typename W = T>
using N3PPolicyNet = nn::Named<policy_names::kLayers, nn::MLPStored<T, W, nn::ReLU, nn::Identity, In, Hidden, Hidden, Out>>;

template <typename T, int In, int Out, typename W = T>
using N3PCorrectionNet = nn::Named<policy_names::kLayers, nn::MLPStored<T, W, nn::Tanh, nn::Tanh, In, 256, 256, Out>>;

template <typename T, int In, int Out, typename W = T>
using QuestSimPolicyNet = nn::Named<policy_names::kLayers, nn::MLPStored<T, W, nn::Tanh, nn::Tanh, In, 400, 300, 200, Out>>;

inline constexpr const char* kN3PPolicyKind = "n3p_policy";
inline constexpr const char* kN3PCorrectionPolicyKind = "n3p_correction_policy";
inline constexpr const char* kQuestSimPolicyKind = "questsim_policy";

}  // namespace sparsebody::networks
