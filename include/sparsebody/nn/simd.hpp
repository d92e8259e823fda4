// SIMD conventions shared by every layer: the batch type, its lane count and buffer padding.
// Internal activation buffers are padded to a whole number of batches and aligned, so kernels use
// aligned full-width loads; callers never pad: public inputs are read element by element and public
// outputs are copied out at their exact size.
#pragma once
#include <xsimd/xsimd.hpp>

namespace sparsebody::nn {

template <typename T>
using Batch = xsimd::batch<T>;

template <typename T>
inline constexpr int kLanes = static_cast<int>(Batch<T>::size);

// Smallest multiple of the lane count that holds n values.
template <typename T>
constexpr int padded(int n) {
  return (n + kLanes<T> - 1) / kLanes<T> * kLanes<T>;
}

// Alignment of internal buffers: a cache line, which is also >= any batch's alignment.
inline constexpr int kBufferAlign = 64;

// A fixed-size, padded, aligned activation buffer. Lives inside per-instance State objects.
template <typename T, int N>
struct alignas(kBufferAlign) PaddedVector {
  static constexpr int size = N;
  static constexpr int storage = padded<T>(N);
  T v[storage] = {};
  T* data() noexcept { return v; }
  const T* data() const noexcept { return v; }
  void set_zero() noexcept {
    for (int i = 0; i < storage; ++i) v[i] = T(0);
  }
};

}  // namespace sparsebody::nn
