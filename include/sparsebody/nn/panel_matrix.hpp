// Matrix-vector product y = W x + b for the weights of Dense and GRU layers.
//
// Storage ("row panels"): W (rows x cols) is cut into panels of kPanelBatches batches of rows; inside
// a panel the values are column-major, so one column of a panel is kPanelBatches contiguous batches:
//
//        panel 0 (rows 0..P-1)      panel 1 (rows P..2P-1)
//   [ w(0..P-1, 0) | w(0..P-1, 1) | ... ][ w(P..2P-1, 0) | ... ]
//
// The kernel then streams every weight exactly once with aligned loads and needs no horizontal
// reduction:  acc[b] += W[panel rows b, j] * broadcast(x[j])  for j = 0..cols-1.
// x is read one scalar at a time, so it needs neither padding nor alignment. Rows are padded with
// zeros to whole batches (the last panel is shorter), so y must hold padded<T>(rows) values.
// At the papers' sizes a GRU step is bound by this weight stream (memory bandwidth), not arithmetic:
// kPanelBatches independent accumulators hide the FMA latency when the weights sit in L1/L2.
#pragma once
#include <cstddef>
#include <cstring>

#include "sparsebody/nn/simd.hpp"

namespace sparsebody::nn {

inline constexpr int kPanelBatches = 8;

// Number of stored values (including zero padding) of a rows x cols matrix in panel layout.
template <typename T>
constexpr std::size_t panel_storage(int rows, int cols) {
  return static_cast<std::size_t>(padded<T>(rows)) * static_cast<std::size_t>(cols);
}

// Read-only view of a panel-layout matrix living in load-time storage.
template <typename T>
struct PanelMatrix {
  const T* data = nullptr;
  int rows = 0;
  int cols = 0;
};

// Writes row-major src (rows x cols) into panel layout at dst (panel_storage values, pre-zeroed).
// `row_map` lets callers re-place rows (the GRU uses it to align each gate block); identity if null.
template <typename T, typename Src>
void pack_panels(const Src* src, int rows, int cols, T* dst, int packed_rows, const int* row_map = nullptr) {
  constexpr int L = kLanes<T>;
  const int prows = padded<T>(packed_rows);
  for (int r = 0; r < rows; ++r) {
    const int pr = row_map ? row_map[r] : r;
    const int panel = pr / (kPanelBatches * L);
    const int panel_row0 = panel * kPanelBatches * L;
    const int height = (prows - panel_row0) < kPanelBatches * L ? (prows - panel_row0) : kPanelBatches * L;
    T* base = dst + static_cast<std::size_t>(panel_row0) * cols;
    for (int c = 0; c < cols; ++c)
      base[static_cast<std::size_t>(c) * height + (pr - panel_row0)] = static_cast<T>(src[static_cast<std::size_t>(r) * cols + c]);
  }
}

namespace detail {
template <typename T, int NB>
inline void panel_gemv(const T* __restrict w, int cols, const T* __restrict x, const T* __restrict bias,
                       T* __restrict y) noexcept {
  using B = Batch<T>;
  constexpr int L = kLanes<T>;
  B acc[NB];
  for (int b = 0; b < NB; ++b) acc[b] = bias ? B::load_aligned(bias + b * L) : B(T(0));
  for (int j = 0; j < cols; ++j) {
    const B xj(x[j]);
    const T* wj = w + static_cast<std::size_t>(j) * NB * L;
    for (int b = 0; b < NB; ++b) acc[b] = xsimd::fma(B::load_aligned(wj + b * L), xj, acc[b]);
  }
  for (int b = 0; b < NB; ++b) acc[b].store_aligned(y + b * L);
}
}  // namespace detail

// y[0 .. padded(rows)) = W x + bias. bias (padded, aligned) may be null. y must be aligned.
template <typename T>
inline void gemv(const PanelMatrix<T>& W, const T* x, const T* bias, T* y) noexcept {
  constexpr int L = kLanes<T>;
  constexpr int P = kPanelBatches * L;
  const int prows = padded<T>(W.rows);
  const T* w = W.data;
  int r0 = 0;
  for (; r0 + P <= prows; r0 += P, w += static_cast<std::size_t>(P) * W.cols)
    detail::panel_gemv<T, kPanelBatches>(w, W.cols, x, bias ? bias + r0 : nullptr, y + r0);
  const int rest = (prows - r0) / L;  // batches in the last, shorter panel
  const T* b = bias ? bias + r0 : nullptr;
  switch (rest) {  // compile-time batch counts keep the accumulators in registers
    case 0: break;
    case 1: detail::panel_gemv<T, 1>(w, W.cols, x, b, y + r0); break;
    case 2: detail::panel_gemv<T, 2>(w, W.cols, x, b, y + r0); break;
    case 3: detail::panel_gemv<T, 3>(w, W.cols, x, b, y + r0); break;
    case 4: detail::panel_gemv<T, 4>(w, W.cols, x, b, y + r0); break;
    case 5: detail::panel_gemv<T, 5>(w, W.cols, x, b, y + r0); break;
    case 6: detail::panel_gemv<T, 6>(w, W.cols, x, b, y + r0); break;
    default: detail::panel_gemv<T, 7>(w, W.cols, x, b, y + r0); break;
  }
}

}  // namespace sparsebody::nn
