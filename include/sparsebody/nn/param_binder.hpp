// Load-time binding of layer parameters: takes tensors from a TensorTable, checks their shapes,
// converts them to the layer scalar type and packs them into aligned storage owned by a WeightStore.
// The WeightStore is allocated once, at load, and is immutable afterwards; layers keep only
// pointers into it, so one store can serve any number of network instances and threads.
#pragma once
#include <cmath>
#include <memory>
#include <type_traits>
#include <string>
#include <vector>

#include "sparsebody/core/aligned_buffer.hpp"
#include "sparsebody/io/tensor_table.hpp"
#include "sparsebody/nn/int8.hpp"
#include "sparsebody/nn/panel_matrix.hpp"

namespace sparsebody::nn {

template <typename T>
class WeightStore {
 public:
  // n zeroed, cache-line aligned values of type U (T, or f16 for half-precision weights).
  template <typename U = T>
  U* allocate(std::size_t n) {
    buffers_.emplace_back((n * sizeof(U) + sizeof(T) - 1) / sizeof(T));
    bytes_ += n * sizeof(U);
    return reinterpret_cast<U*>(buffers_.back().data());
  }
  // Bytes of parameters (including SIMD padding) one forward pass streams.
  std::size_t bytes() const noexcept { return bytes_; }
  // Calls f(data, bytes) for every buffer, in allocation order (benchmarks stream the same bytes
  // with a plain read to measure the memory floor of a step).
  template <class F>
  void for_each_buffer(F&& f) const {
    for (const auto& b : buffers_) f(static_cast<const void*>(b.data()), b.size() * sizeof(T));
  }

 private:
  std::vector<AlignedBuffer<T>> buffers_;
  std::size_t bytes_ = 0;
};

template <typename T>
class ParamBinder {
 public:
  ParamBinder(io::TensorTable& table, WeightStore<T>& store) : table_(table), store_(store) {}

  // Tensor `name` of shape [rows, cols] packed as panels with `packed_rows` rows; row r goes to
  // row_map[r] (identity when null). Padding rows are zero. W: stored type (T, f16, or q8).
  template <typename W = T>
  PanelMatrix<T, W> matrix(const std::string& name, int rows, int cols, int packed_rows = -1,
                           const int* row_map = nullptr) {
    if (packed_rows < 0) packed_rows = rows;
    const io::Tensor& t = table_.take(name, {rows, cols});
    if constexpr (std::is_same_v<W, q8>) {
      static_assert(std::is_same_v<T, float>, "q8 weights are for float networks");
      if (cols > kQ8MaxCols)
        throw LoadError(table_.source(), "tensor '" + name + "': " + std::to_string(cols) +
                                             " columns, more than int8 weight storage takes (" + std::to_string(kQ8MaxCols) + ")");
      for (std::size_t i = 0; i < t.values.size(); ++i)
        if (!std::isfinite(t.values[i]))
          throw LoadError(table_.source(), "tensor '" + name + "': non-finite value at flat index " + std::to_string(i));
      const int prows = padded<T>(packed_rows);
      auto* q = store_.template allocate<std::int8_t>(static_cast<std::size_t>(prows) * 4 * q8_groups(cols));
      auto* scale = store_.template allocate<float>(static_cast<std::size_t>(prows));
      auto* sum = store_.template allocate<std::int32_t>(static_cast<std::size_t>(prows));
      pack_q8(t.values.data(), rows, cols, q, scale, sum, packed_rows, row_map);
      return PanelMatrix<T, W>{q, scale, sum, packed_rows, cols};
    } else {
      if constexpr (std::is_same_v<W, f16>) {
        for (std::size_t i = 0; i < t.values.size(); ++i)
          if (std::abs(t.values[i]) > kF16Max)
            throw LoadError(table_.source(), "tensor '" + name + "': value " + std::to_string(t.values[i]) + " at flat index " +
                                                 std::to_string(i) + " does not fit float16 weight storage");
      }
      W* dst = store_.template allocate<W>(panel_storage<T>(packed_rows, cols));
      pack_panels<T, W>(t.values.data(), rows, cols, dst, packed_rows, row_map);
      return PanelMatrix<T, W>{dst, packed_rows, cols};
    }
  }

  // Tensor `name` of shape [n] into an aligned, zero-padded array of `packed_n` values.
  const T* vector(const std::string& name, int n, int packed_n = -1, const int* index_map = nullptr) {
    if (packed_n < 0) packed_n = n;
    const io::Tensor& t = table_.take(name, {n});
    T* dst = store_.allocate(static_cast<std::size_t>(padded<T>(packed_n)));
    for (int i = 0; i < n; ++i) dst[index_map ? index_map[i] : i] = static_cast<T>(t.values[i]);
    return dst;
  }

  io::TensorTable& table() noexcept { return table_; }

 private:
  io::TensorTable& table_;
  WeightStore<T>& store_;
};

}  // namespace sparsebody::nn
