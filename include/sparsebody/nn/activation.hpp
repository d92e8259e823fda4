// Element-wise activations, applied in place to a padded buffer. Each is a tag type with
//   template <typename T, int N> static void apply(T* y) noexcept
// so it can be fused into Dense or used as a stand-alone layer (Activation<T, N, Act>).
// Formulas follow PyTorch: ELU(alpha=1) uses expm1; softmax subtracts the group max first.
#pragma once
#include <cmath>

#include "sparsebody/nn/simd.hpp"

namespace sparsebody::nn {

struct Identity {
  static constexpr const char* name = "identity";
  template <typename T, int N>
  static void apply(T*) noexcept {}
};

struct ReLU {
  static constexpr const char* name = "relu";
  template <typename T, int N>
  static void apply(T* y) noexcept {
    using B = Batch<T>;
    for (int i = 0; i < padded<T>(N); i += kLanes<T>) xsimd::max(B::load_aligned(y + i), B(T(0))).store_aligned(y + i);
  }
};

struct Tanh {
  static constexpr const char* name = "tanh";
  template <typename T, int N>
  static void apply(T* y) noexcept {
    using B = Batch<T>;
    for (int i = 0; i < padded<T>(N); i += kLanes<T>) xsimd::tanh(B::load_aligned(y + i)).store_aligned(y + i);
  }
};

// sigma(x) = 1 / (1 + exp(-x))
template <typename T>
inline Batch<T> sigmoid(const Batch<T>& x) noexcept {
  return Batch<T>(T(1)) / (Batch<T>(T(1)) + xsimd::exp(-x));
}

struct Sigmoid {
  static constexpr const char* name = "sigmoid";
  template <typename T, int N>
  static void apply(T* y) noexcept {
    using B = Batch<T>;
    for (int i = 0; i < padded<T>(N); i += kLanes<T>) sigmoid<T>(B::load_aligned(y + i)).store_aligned(y + i);
  }
};

// ELU with alpha = 1: x for x > 0, exp(x) - 1 otherwise.
struct ELU {
  static constexpr const char* name = "elu";
  template <typename T, int N>
  static void apply(T* y) noexcept {
    using B = Batch<T>;
    for (int i = 0; i < padded<T>(N); i += kLanes<T>) {
      const B x = B::load_aligned(y + i);
      xsimd::select(x > B(T(0)), x, xsimd::expm1(xsimd::min(x, B(T(0))))).store_aligned(y + i);
    }
  }
};

// Softmax over consecutive groups of Group values (N must be a multiple of Group), e.g. Group = 2
// for LoBSTr's per-foot contact logits. Groups are tiny, so this is scalar.
template <int Group>
struct Softmax {
  static constexpr const char* name = "softmax";
  template <typename T, int N>
  static void apply(T* y) noexcept {
    static_assert(N % Group == 0, "softmax: output size must be a multiple of the group size");
    for (int g = 0; g < N; g += Group) {
      T m = y[g];
      for (int i = 1; i < Group; ++i) m = y[g + i] > m ? y[g + i] : m;
      T s = 0;
      for (int i = 0; i < Group; ++i) s += (y[g + i] = std::exp(y[g + i] - m));
      for (int i = 0; i < Group; ++i) y[g + i] /= s;
    }
  }
};

}  // namespace sparsebody::nn
