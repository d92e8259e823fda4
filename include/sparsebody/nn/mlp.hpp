// MLP<T, HiddenAct, OutAct, S0, S1, ..., Sk>: Dense layers S0->S1->...->Sk, HiddenAct after every
// layer but the last, OutAct after the last. Its tensors are named like the children of an
// nn.Sequential / nn.ModuleList of nn.Linear: "<i>.weight", "<i>.bias".
#pragma once
#include <tuple>
#include <utility>

#include "sparsebody/nn/compose.hpp"
#include "sparsebody/nn/dense.hpp"

namespace sparsebody::nn {

namespace detail {
template <typename T, typename HiddenAct, typename OutAct, typename Sizes, typename Idx>
struct MlpBuilder;
template <typename T, typename HiddenAct, typename OutAct, int... S, std::size_t... I>
struct MlpBuilder<T, HiddenAct, OutAct, std::integer_sequence<int, S...>, std::index_sequence<I...>> {
  static constexpr int sizes[] = {S...};
  static constexpr std::size_t n = sizeof...(I);
  using type = Sequential<Dense<T, sizes[I], sizes[I + 1], std::conditional_t<I + 1 == n, OutAct, HiddenAct>>...>;
};
}  // namespace detail

template <typename T, typename HiddenAct, typename OutAct, int... Sizes>
using MLP = typename detail::MlpBuilder<T, HiddenAct, OutAct, std::integer_sequence<int, Sizes...>,
                                        std::make_index_sequence<sizeof...(Sizes) - 1>>::type;

}  // namespace sparsebody::nn
