// The interface every layer and composite implements (checked at compile time by IsLayer):
//
//   using scalar = T;                       float or double
//   static constexpr int in_size, out_size; exact (unpadded) sizes
//   struct Params;                          pointers into load-time WeightStore (cheap to copy)
//   struct State;                           per-instance mutable state and scratch (fixed size)
//   static void bind(Params&, ParamBinder<T>&, const std::string& prefix);        load time
//   static void forward(const Params&, State&, const T* x, T* y) noexcept;        per step
//   static void reset(State&) noexcept;                                           clears recurrence
//
// forward() reads x[0..in_size) element-wise (any alignment, no padding needed) and writes y, an
// aligned buffer of padded<T>(out_size) values (internal buffers are PaddedVector).
// Tensor names follow PyTorch's state_dict: `prefix` is the module path, e.g. "gru." or "layers.0.".
#pragma once
#include <string>
#include <type_traits>

#include "sparsebody/nn/param_binder.hpp"

namespace sparsebody::nn {

struct NoState {
  void reset() noexcept {}
};

}  // namespace sparsebody::nn
