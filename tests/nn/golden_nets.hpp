// C++ twins of the committed golden models in weights_tool/golden.py (SMALL).
#pragma once
#include "sparsebody/networks/lobstr_net.hpp"
#include "sparsebody/networks/n3p_predictor_net.hpp"
#include "sparsebody/networks/policy_nets.hpp"
#include "sparsebody/nn/activation.hpp"
#include "sparsebody/nn/compose.hpp"
#include "sparsebody/nn/dense.hpp"
#include "sparsebody/nn/gru.hpp"
#include "sparsebody/nn/mlp.hpp"

namespace sparsebody_test {
namespace nn = sparsebody::nn;
namespace net = sparsebody::networks;
inline constexpr char kNet[] = "net";
inline constexpr char kGruName[] = "gru";

// nets.LayerZoo: nn.Sequential(Linear, ReLU, Linear(no bias), Tanh, Linear, Sigmoid, Linear, ELU,
// Linear, GroupSoftmax(2)) -> indexed names "0.weight", "2.weight", ...
template <typename T>
using ZooNet = nn::Sequential<nn::Dense<T, 13, 29>, nn::Activation<T, 29, nn::ReLU>, nn::Dense<T, 29, 31, nn::Identity, false>,
                              nn::Activation<T, 31, nn::Tanh>, nn::Dense<T, 31, 17>, nn::Activation<T, 17, nn::Sigmoid>,
                              nn::Dense<T, 17, 19>, nn::Activation<T, 19, nn::ELU>, nn::Dense<T, 19, 8>,
                              nn::Activation<T, 8, nn::Softmax<2>>>;
template <typename T>
using GruStackNet = nn::Named<kGruName, nn::GRU<T, 11, 23, 2>>;
template <typename T>
using LoBSTrSmall = net::LoBSTrNet<T, 40, 24>;
template <typename T>
using N3PSmall = net::N3PPredictorNet<T, 45, 20, 13>;
template <typename T>
using PolicySmall = net::N3PPolicyNet<T, 50, 9, 32>;
template <typename T>
using MlpTanhSmall = nn::Named<net::policy_names::kLayers, nn::MLP<T, nn::Tanh, nn::Tanh, 20, 16, 12, 8, 5>>;

// Paper sizes (weights_tool/golden.py PAPER).
template <typename T>
using LoBSTr1024 = net::LoBSTrNet<T, 1024, 128>;
template <typename T>
using LoBSTr256 = net::LoBSTrNet<T, 256, 128>;
template <typename T>
using N3PSignal = net::N3PPredictorNet<T, 45, 64, 12>;
template <typename T>
using N3PLower = net::N3PPredictorNet<T, 12, 128, 113>;
template <typename T>
using N3PUpper = net::N3PPredictorNet<T, 45, 128, 201>;
template <typename T>
using N3PPolicy = net::N3PPolicyNet<T, 868, 72>;
template <typename T>
using QuestSimPolicy = net::QuestSimPolicyNet<T, 475, 33>;
}  // namespace sparsebody_test
