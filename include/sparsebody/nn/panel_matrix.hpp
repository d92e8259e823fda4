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

#include <type_traits>

#include "sparsebody/nn/half.hpp"
#include "sparsebody/nn/simd.hpp"

#if defined(__aarch64__) && defined(__ARM_NEON)
#include <arm_neon.h>
#endif

namespace sparsebody::nn {

inline constexpr int kPanelBatches = 8;
// Most instances one batched step (nn/batch.hpp) takes: its pointer arrays live on the stack.
inline constexpr int kBatchMax = 64;

// Number of stored values (including zero padding) of a rows x cols matrix in panel layout.
template <typename T>
constexpr std::size_t panel_storage(int rows, int cols) {
  return static_cast<std::size_t>(padded<T>(rows)) * static_cast<std::size_t>(cols);
}

// Read-only view of a panel-layout matrix living in load-time storage. T is the arithmetic type,
// W the stored weight type: T itself, or f16 (half the bytes, widened to float in registers).
template <typename T, typename W = T>
struct PanelMatrix {
  static_assert(std::is_same_v<W, T> || (std::is_same_v<W, f16> && std::is_same_v<T, float>),
                "weights are stored as the scalar type, or as f16 for float networks");
  const W* data = nullptr;
  int rows = 0;
  int cols = 0;
};

// Loads one batch of stored weights as a batch of T.
template <typename T, typename W>
inline Batch<T> load_weights(const W* p) noexcept {
  if constexpr (std::is_same_v<W, T>) {
    return Batch<T>::load_aligned(p);
  } else {
#if defined(__AVX512F__)
    if constexpr (kLanes<float> == 16) return Batch<float>(_mm512_cvtph_ps(_mm256_load_si256(reinterpret_cast<const __m256i*>(p))));
#endif
#if defined(__F16C__) && defined(__AVX__)
    if constexpr (kLanes<float> == 8) return Batch<float>(_mm256_cvtph_ps(_mm_load_si128(reinterpret_cast<const __m128i*>(p))));
#endif
#if defined(__F16C__)
    if constexpr (kLanes<float> == 4) return Batch<float>(_mm_cvtph_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p))));
#endif
#if defined(__aarch64__) && defined(__ARM_NEON)
    // fcvtl: exact widening (every binary16 value is a float), so it equals to_float_portable.
    if constexpr (kLanes<float> == 4) return Batch<float>(vcvt_f32_f16(vreinterpret_f16_u16(vld1_u16(reinterpret_cast<const std::uint16_t*>(p)))));
#endif
    alignas(kBufferAlign) float tmp[kLanes<float>];  // portable path (no F16C): correct, slower
    for (int i = 0; i < kLanes<float>; ++i) tmp[i] = to_float(p[i]);
    return Batch<float>::load_aligned(tmp);
  }
}

// Writes row-major src (rows x cols) into panel layout at dst (panel_storage values, pre-zeroed).
// `row_map` lets callers re-place rows (the GRU uses it to align each gate block); identity if null.
// T decides the panel geometry (lanes of the arithmetic type), W the stored element type.
template <typename T, typename W = T, typename Src>
void pack_panels(const Src* src, int rows, int cols, W* dst, int packed_rows, const int* row_map = nullptr) {
  constexpr int L = kLanes<T>;
  const int prows = padded<T>(packed_rows);
  for (int r = 0; r < rows; ++r) {
    const int pr = row_map ? row_map[r] : r;
    const int panel = pr / (kPanelBatches * L);
    const int panel_row0 = panel * kPanelBatches * L;
    const int height = (prows - panel_row0) < kPanelBatches * L ? (prows - panel_row0) : kPanelBatches * L;
    W* base = dst + static_cast<std::size_t>(panel_row0) * cols;
    for (int c = 0; c < cols; ++c)
      base[static_cast<std::size_t>(c) * height + (pr - panel_row0)] =
          from_double<W>(static_cast<double>(src[static_cast<std::size_t>(r) * cols + c]));
  }
}

namespace detail {
// Independent FMA chains to keep in flight: an FMA has ~4 cycles latency and 2 issue per cycle, so
// >= 8 chains hide it; AVX-512 has 32 vector registers, room for 16. A panel of NB < chains batches
// therefore splits its columns over K = chains / NB accumulator sets (summed at the end).
template <typename T>
inline constexpr int kFmaChains = sizeof(Batch<T>) >= 64 ? 16 : 8;

template <typename T, typename W, int NB>
inline void panel_gemv(const W* __restrict w, int cols, const T* __restrict x, const T* __restrict bias,
                       T* __restrict y) noexcept {
  using B = Batch<T>;
  constexpr int L = kLanes<T>;
  constexpr int K = kFmaChains<T> / NB > 1 ? kFmaChains<T> / NB : 1;
  B acc[K][NB];
  for (int k = 0; k < K; ++k)
    for (int b = 0; b < NB; ++b) acc[k][b] = B(T(0));
  int j = 0;
  for (; j + K <= cols; j += K) {
    for (int k = 0; k < K; ++k) {
      const B xj(x[j + k]);
      const W* wj = w + static_cast<std::size_t>(j + k) * NB * L;
      for (int b = 0; b < NB; ++b) acc[k][b] = xsimd::fma(load_weights<T, W>(wj + b * L), xj, acc[k][b]);
    }
  }
  for (; j < cols; ++j) {
    const B xj(x[j]);
    const W* wj = w + static_cast<std::size_t>(j) * NB * L;
    for (int b = 0; b < NB; ++b) acc[0][b] = xsimd::fma(load_weights<T, W>(wj + b * L), xj, acc[0][b]);
  }
  for (int b = 0; b < NB; ++b) {
    B sum = bias ? B::load_aligned(bias + b * L) : B(T(0));
    for (int k = 0; k < K; ++k) sum += acc[k][b];
    sum.store_aligned(y + b * L);
  }
}
}  // namespace detail

// y[0 .. padded(rows)) = W x + bias. bias (padded, aligned) may be null. y must be aligned.
template <typename T, typename Wt>
inline void gemv(const PanelMatrix<T, Wt>& W, const T* x, const T* bias, T* y) noexcept {
  static_assert(kPanelBatches == 8, "the tail switch below handles up to 7 batches");
  constexpr int L = kLanes<T>;
  constexpr int P = kPanelBatches * L;
  const int prows = padded<T>(W.rows);
  const Wt* w = W.data;
  int r0 = 0;
  for (; r0 + P <= prows; r0 += P, w += static_cast<std::size_t>(P) * W.cols)
    detail::panel_gemv<T, Wt, kPanelBatches>(w, W.cols, x, bias ? bias + r0 : nullptr, y + r0);
  const int rest = (prows - r0) / L;  // batches in the last, shorter panel
  const T* b = bias ? bias + r0 : nullptr;
  switch (rest) {  // compile-time batch counts keep the accumulators in registers
    case 0: break;
    case 1: detail::panel_gemv<T, Wt, 1>(w, W.cols, x, b, y + r0); break;
    case 2: detail::panel_gemv<T, Wt, 2>(w, W.cols, x, b, y + r0); break;
    case 3: detail::panel_gemv<T, Wt, 3>(w, W.cols, x, b, y + r0); break;
    case 4: detail::panel_gemv<T, Wt, 4>(w, W.cols, x, b, y + r0); break;
    case 5: detail::panel_gemv<T, Wt, 5>(w, W.cols, x, b, y + r0); break;
    case 6: detail::panel_gemv<T, Wt, 6>(w, W.cols, x, b, y + r0); break;
    default: detail::panel_gemv<T, Wt, 7>(w, W.cols, x, b, y + r0); break;
  }
}

// Batched product for n instances sharing W (NetworkBatch, nn/batch.hpp): y[i] = W x[i] + bias for
// i < n. Each y[i] equals gemv(W, x[i], bias, y[i]) bit for bit: every instance keeps the single
// product's FMA chains (same K accumulator sets, same column order, same final sum). What changes is
// the loop order: one batch of rows at a time, each weight batch loaded once for a tile of up to
// kFmaChains / K instances, so a weight comes from memory once per frame for all instances and
// from cache once per tile.
namespace detail {
// R row batches (b .. b+R-1, R = 1 or 2) for NI instances. With R = 2 each instance's broadcast
// x[i][j] feeds both batches, so a step of 2 weight loads and NI broadcasts does 2 NI FMAs (R = 1:
// 1 + NI loads for NI). Same accumulators, column order and final sums as panel_gemv: bit for bit.
template <typename T, typename W, int NB, int R, int NI>
inline void panel_gemv_tile(const W* __restrict w, int cols, int b, const T* const* x, const T* bias, T* const* y,
                            int row0) noexcept {
  using B = Batch<T>;
  constexpr int L = kLanes<T>;
  constexpr int K = kFmaChains<T> / NB > 1 ? kFmaChains<T> / NB : 1;  // as panel_gemv
  B acc[K][R][NI];
  for (int k = 0; k < K; ++k)
    for (int r = 0; r < R; ++r)
      for (int i = 0; i < NI; ++i) acc[k][r][i] = B(T(0));
  const W* wb = w + b * L;
  auto column = [&](int j, int k) {  // column j into accumulator set k
    const W* wj = wb + static_cast<std::size_t>(j) * NB * L;
    B wv[R];
    for (int r = 0; r < R; ++r) wv[r] = load_weights<T, W>(wj + r * L);
    for (int i = 0; i < NI; ++i) {
      const B xi(x[i][j]);
      for (int r = 0; r < R; ++r) acc[k][r][i] = xsimd::fma(wv[r], xi, acc[k][r][i]);
    }
  };
  int j = 0;
  for (; j + K <= cols; j += K)
    for (int k = 0; k < K; ++k) column(j + k, k);
  for (; j < cols; ++j) column(j, 0);
  for (int r = 0; r < R; ++r)
    for (int i = 0; i < NI; ++i) {
      B sum = bias ? B::load_aligned(bias + (b + r) * L) : B(T(0));
      for (int k = 0; k < K; ++k) sum += acc[k][r][i];
      sum.store_aligned(y[i] + row0 + (b + r) * L);
    }
}

// Vector registers of the target: 32 with AVX-512 or on AArch64, else 16 (AVX2, SSE2).
#if defined(__AVX512F__) || defined(__aarch64__)
inline constexpr int kVectorRegisters = 32;
#else
inline constexpr int kVectorRegisters = 16;
#endif
// Two-batch tiles pay where loads bound the tile (two per FMA cycle against 2 FMAs): the AVX2 build
// on Zen 4 ran batches of 16 and 64 instances 1.11-1.29x faster. The AVX-512 build on the same CPU
// ran them 0.90-1.03x (its 512-bit FMAs, not its loads, bound it there), so AVX-512 keeps one-batch
// tiles.
#if defined(__AVX512F__)
inline constexpr bool kTwoBatchTiles = false;
#else
inline constexpr bool kTwoBatchTiles = true;
#endif

template <typename T, typename W, int NB>
inline void panel_gemv_batch(const W* w, int cols, int n, const T* const* x, const T* bias, T* const* y,
                             int row0) noexcept {
  constexpr int K = kFmaChains<T> / NB > 1 ? kFmaChains<T> / NB : 1;
  constexpr int NI = 8 / K > 1 ? 8 / K : 1;  // K * NI <= 8 accumulators (+ weights, broadcasts)
  // Two-batch tiles (even NB): 2 K NI2 accumulators, 2 weights and a broadcast in the registers.
  constexpr int NI2 = (kVectorRegisters - 5) / (2 * K) < 8 ? (kVectorRegisters - 5) / (2 * K) : 8;
  int i0 = 0;  // instances [0, i0) done by two-batch tiles
  if constexpr (kTwoBatchTiles && NB % 2 == 0 && NI2 >= 2) {
    i0 = n / NI2 * NI2;
    for (int b = 0; b < NB; b += 2)
      for (int i = 0; i < i0; i += NI2) panel_gemv_tile<T, W, NB, 2, NI2>(w, cols, b, x + i, bias, y + i, row0);
  }
  const int tiled = NI > 1 ? i0 + (n - i0) / NI * NI : i0;
  for (int b = 0; b < NB; ++b)
    for (int i = i0; i < tiled; i += NI) panel_gemv_tile<T, W, NB, 1, NI>(w, cols, b, x + i, bias, y + i, row0);
  // The instances left over (all of them when a tile would hold one): the single product, which
  // keeps all NB * K accumulators busy instead of K.
  for (int i = tiled; i < n; ++i) panel_gemv<T, W, NB>(w, cols, x[i], bias, y[i] + row0);
}
}  // namespace detail

template <typename T, typename Wt>
inline void gemv_batch(const PanelMatrix<T, Wt>& W, int n, const T* const* x, const T* bias, T* const* y) noexcept {
  constexpr int L = kLanes<T>;
  constexpr int P = kPanelBatches * L;
  const int prows = padded<T>(W.rows);
  const Wt* w = W.data;
  int r0 = 0;
  for (; r0 + P <= prows; r0 += P, w += static_cast<std::size_t>(P) * W.cols)
    detail::panel_gemv_batch<T, Wt, kPanelBatches>(w, W.cols, n, x, bias ? bias + r0 : nullptr, y, r0);
  const int rest = (prows - r0) / L;
  const T* b = bias ? bias + r0 : nullptr;
  switch (rest) {
    case 0: break;
    case 1: detail::panel_gemv_batch<T, Wt, 1>(w, W.cols, n, x, b, y, r0); break;
    case 2: detail::panel_gemv_batch<T, Wt, 2>(w, W.cols, n, x, b, y, r0); break;
    case 3: detail::panel_gemv_batch<T, Wt, 3>(w, W.cols, n, x, b, y, r0); break;
    case 4: detail::panel_gemv_batch<T, Wt, 4>(w, W.cols, n, x, b, y, r0); break;
    case 5: detail::panel_gemv_batch<T, Wt, 5>(w, W.cols, n, x, b, y, r0); break;
    case 6: detail::panel_gemv_batch<T, Wt, 6>(w, W.cols, n, x, b, y, r0); break;
    default: detail::panel_gemv_batch<T, Wt, 7>(w, W.cols, n, x, b, y, r0); break;
  }
}

}  // namespace sparsebody::nn
