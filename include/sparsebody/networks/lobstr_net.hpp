// LoBSTr network (Eurographics 2021, §3.3): a one-layer GRU encodes the 37 tracker features,
//   h_i = GRU(h_{i-1}, x_i | theta_g);   l_i = ReLU(theta_l1 h_i)
// then two linear heads give the 8 lower-body joint rotations in 6D (theta_lp, 48 values) and the
// per-foot contact probabilities (theta_lc, 2 feet x {no contact, contact}, softmax per foot).
// Output layout: [pose 48 | contact_left(2) | contact_right(2)].
// Paper sizes: H = 1024, Latent = 128. Reference module: weights_tool/nets.py LoBSTrNet.
#pragma once
#include "sparsebody/nn/compose.hpp"
#include "sparsebody/nn/dense.hpp"
#include "sparsebody/nn/gru.hpp"

namespace sparsebody::networks {

namespace lobstr_names {
inline constexpr char kGru[] = "gru";
inline constexpr char kLatent[] = "latent";
inline constexpr char kPose[] = "pose";
inline constexpr char kContact[] = "contact";
}  // namespace lobstr_names

inline constexpr int kLoBSTrFeatures = 37;      // 4 x 9 velocities + reference height (Appendix 1)
inline constexpr int kLoBSTrPoseOutputs = 48;   // 8 joints x 6D
inline constexpr int kLoBSTrContactOutputs = 4; // 2 feet x 2 classes

// W: stored weight type of the GRU and the latent layer (T, or nn::f16 to halve the bytes per step).
template <typename T, int Hidden = 1024, int Latent = 128, int In = kLoBSTrFeatures, typename W = T>
using LoBSTrNet = nn::Sequential<
    nn::Named<lobstr_names::kGru, nn::GRU<T, In, Hidden, 1, W>>,
    nn::Named<lobstr_names::kLatent, nn::Dense<T, Hidden, Latent, nn::ReLU, true, W>>,
    nn::Parallel<nn::Named<lobstr_names::kPose, nn::Dense<T, Latent, kLoBSTrPoseOutputs>>,
                 nn::Named<lobstr_names::kContact, nn::Dense<T, Latent, kLoBSTrContactOutputs, nn::Softmax<2>>>>>;

inline constexpr const char* kLoBSTrKind = "lobstr";

}  // namespace sparsebody::networks
