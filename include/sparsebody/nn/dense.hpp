// Fully connected layer y = act(W x + b), PyTorch nn.Linear semantics (weight [Out, In], bias [Out])
// with an optional fused activation (see activation.hpp). W is the stored weight type: T, or f16 to
// halve the bytes a step streams (biases stay in T).
#pragma once
#include "sparsebody/nn/activation.hpp"
#include "sparsebody/nn/layer.hpp"

namespace sparsebody::nn {

template <typename T, int In, int Out, typename Act = Identity, bool HasBias = true, typename W = T>
struct Dense {
  static_assert(In > 0 && Out > 0, "Dense: sizes must be positive");
  using scalar = T;
  static constexpr int in_size = In;
  static constexpr int out_size = Out;

  struct Params {
    PanelMatrix<T, W> weight;  // W: [Out, In]
    const T* bias = nullptr; // b: [Out], padded; null without bias
  };
  using State = NoState;

  static void bind(Params& p, ParamBinder<T>& b, const std::string& prefix) {
    p.weight = b.template matrix<W>(prefix + "weight", Out, In);
    if constexpr (HasBias) p.bias = b.vector(prefix + "bias", Out);
  }

  static void forward(const Params& p, State&, const T* x, T* y) noexcept {
    gemv(p.weight, x, p.bias, y);  // y = W x + b
    Act::template apply<T, Out>(y);
  }
  // n instances at once (nn/batch.hpp): equal to n forward() calls, bit for bit.
  static void forward_batch(const Params& p, State* const*, int n, const T* const* x, T* const* y) noexcept {
    gemv_batch(p.weight, n, x, p.bias, y);
    for (int i = 0; i < n; ++i) Act::template apply<T, Out>(y[i]);
  }
  static void reset(State&) noexcept {}
};

// A parameter-free activation as its own layer, for nets mirroring nn.Sequential(Linear, ReLU, ...):
// it occupies an index in the Sequential like the torch module does.
template <typename T, int N, typename Act>
struct Activation {
  using scalar = T;
  static constexpr int in_size = N;
  static constexpr int out_size = N;
  struct Params {};
  using State = NoState;
  static void bind(Params&, ParamBinder<T>&, const std::string&) {}
  static void forward(const Params&, State&, const T* x, T* y) noexcept {
    if (x != y)
      for (int i = 0; i < N; ++i) y[i] = x[i];
    Act::template apply<T, N>(y);
  }
  static void forward_batch(const Params& p, State* const* s, int n, const T* const* x, T* const* y) noexcept {
    for (int i = 0; i < n; ++i) forward(p, *s[i], x[i], y[i]);
  }
  static void reset(State&) noexcept {}
};

}  // namespace sparsebody::nn
