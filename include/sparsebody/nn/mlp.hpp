// MLP<T, HiddenAct, OutAct, S0, S1, ..., Sk>: Dense layers S0->S1->...->Sk, HiddenAct after every
// layer but the last, OutAct after the last. Its tensors are named like the children of an
// nn.Sequential / nn.ModuleList of nn.Linear: "<i>.weight", "<i>.bias".
// MLPStored<T, W, ...> is the same with weights stored as W (T, or f16 to halve the bytes per step).
#pragma once
#include <tuple>
#include <utility>

#include "sparsebody/nn/compose.hpp"
#include "sparsebody/nn/dense.hpp"

namespace sparsebody::nn {

namespace detail {
template <typename T, typename W, typename HiddenAct, typename OutAct, typename Sizes, typename Idx>
struct MlpBuilder;
template <typename T, typename W, typename HiddenAct, typename OutAct, int... S, std::size_t... I>
struct MlpBuilder<T, W, HiddenAct, OutAct, std::integer_sequence<int, S...>, std::index_sequence<I...>> {
  static constexpr int sizes[sizeof...(S)] = {S...};  // the bound spelled out: clang reads no element of an unbounded array in a constant expression
  static constexpr std::size_t n = sizeof...(I);
  using type =
      Sequential<Dense<T, sizes[I], sizes[I + 1], std::conditional_t<I + 1 == n, OutAct, HiddenAct>, true, W>...>;
};
}  // namespace detail

template <typename T, typename W, typename HiddenAct, typename OutAct, int... Sizes>
using MLPStored = typename detail::MlpBuilder<T, W, HiddenAct, OutAct, std::integer_sequence<int, Sizes...>,
                                              std::make_index_sequence<sizeof...(Sizes) - 1>>::type;

template <typename T, typename HiddenAct, typename OutAct, int... Sizes>
using MLP = MLPStored<T, T, HiddenAct, OutAct, Sizes...>;

}  // namespace sparsebody::nn
