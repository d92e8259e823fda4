// Neural3Points sub-predictor (SCA 2022, §4.1): one linear encoder, three GRU layers, one linear
// decoder. Gsig, Glo and Gup share this shape with hidden sizes 64, 128 and 128. Dropout (0.1 after
// the encoder, 0.05 before the decoder) exists only in training and is absent here.
// Reference module: weights_tool/nets.py N3PPredictor ("encoder.", "gru.", "decoder." tensors).
#pragma once
#include "sparsebody/nn/compose.hpp"
#include "sparsebody/nn/dense.hpp"
#include "sparsebody/nn/gru.hpp"

namespace sparsebody::networks {

namespace n3p_names {
inline constexpr char kEncoder[] = "encoder";
inline constexpr char kGru[] = "gru";
inline constexpr char kDecoder[] = "decoder";
}  // namespace n3p_names

// W: stored weight type (T, or nn::f16 to halve the bytes per step).
template <typename T, int In, int Hidden, int Out, int GruLayers = 3, typename W = T>
using N3PPredictorNet = nn::Sequential<nn::Named<n3p_names::kEncoder, nn::Dense<T, In, Hidden, nn::Identity, true, W>>,
                                       nn::Named<n3p_names::kGru, nn::GRU<T, Hidden, Hidden, GruLayers, W>>,
                                       nn::Named<n3p_names::kDecoder, nn::Dense<T, Hidden, Out, nn::Identity, true, W>>>;

inline constexpr const char* kN3PSignalKind = "n3p_signal";
inline constexpr const char* kN3PLowerKind = "n3p_lower";
inline constexpr const char* kN3PUpperKind = "n3p_upper";

}  // namespace sparsebody::networks
