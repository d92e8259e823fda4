// int8 weight storage with dynamic activation quantization ("q8"), an opt-in for float networks
// whose per-step weight stream does not fit in L2 in float (or f16): a quarter of the float bytes.
//
// Scheme (the one torch.ao.quantization.quantize_dynamic uses for Linear/GRU, symmetric variant):
//   weights, per output row r, at load:  s_r = max_c |W_rc| / 127,  Q_rc = round(W_rc / s_r) in [-127, 127]
//   input x, per product, at run time:   s_x = max_j |x_j| / 127,   q_j  = round(x_j / s_x)  in [-127, 127]
//   y_r = b_r + s_r s_x sum_j Q_rj q_j   (the sum exact in int32)
// AVX-512 VNNI's vpdpbusd multiplies unsigned by signed bytes, so the kernel feeds u_j = q_j + 128
// and subtracts 128 sum_j Q_rj (precomputed per row): sum_j Q_rj u_j - 128 R_r = sum_j Q_rj q_j.
// One vpdpbusd does 64 multiply-adds (16 rows x 4 columns), so the product is bound by the 1-byte
// weight stream, not by arithmetic as the f16 path is (one vcvtph2ps per 16 weights).
//
// Accuracy: each weight keeps ~8 bits relative to its row's largest, each input ~8 bits relative
// to the vector's largest; typical GEMV outputs differ from float by ~1e-3 relative. Measure the
// effect on your task before shipping it (the Neural3Points README section gives ours).
//
// Layout (rows grouped like panel_matrix.hpp: panels of kPanelBatches batches of L = kLanes<float>
// rows): inside a panel, for each group g of 4 columns, NB batches x L rows x 4 bytes, row-major
// within the 4 bytes. Columns are padded to a multiple of 4 with zeros, rows with zero rows.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "sparsebody/nn/panel_matrix.hpp"

#if defined(__AVX512F__) && defined(__AVX512VNNI__) && defined(__AVX512BW__)
#include <immintrin.h>
#define SPARSEBODY_Q8_AVX512 1
#endif

namespace sparsebody::nn {

struct q8 {
  std::int8_t value = 0;
};

// Longest input a q8 product takes (its quantized copy lives on the stack: no allocation).
inline constexpr int kQ8MaxCols = 4096;

constexpr int q8_groups(int cols) { return (cols + 3) / 4; }

template <>
struct PanelMatrix<float, q8> {
  const std::int8_t* data = nullptr;     // Q, panel layout above
  const float* row_scale = nullptr;      // s_r, padded rows (padding 0)
  const std::int32_t* row_sum = nullptr; // R_r = sum_c Q_rc, padded rows
  int rows = 0;                          // packed rows; the product writes padded<float>(rows)
  int cols = 0;
};

// Quantizes row-major src (rows x cols) into the q8 layout. dst holds padded<float>(packed_rows) *
// 4 * q8_groups(cols) bytes (pre-zeroed); scale and sum hold padded<float>(packed_rows) values.
template <typename Src>
void pack_q8(const Src* src, int rows, int cols, std::int8_t* dst, float* scale, std::int32_t* sum,
             int packed_rows, const int* row_map = nullptr) {
  constexpr int L = kLanes<float>;
  const int prows = padded<float>(packed_rows);
  const int groups = q8_groups(cols);
  for (int r = 0; r < rows; ++r) {
    const int pr = row_map ? row_map[r] : r;
    const Src* w = src + static_cast<std::size_t>(r) * cols;
    double amax = 0;
    for (int c = 0; c < cols; ++c) amax = std::max(amax, std::abs(static_cast<double>(w[c])));
    const float s = amax > 0 ? static_cast<float>(amax / 127.0) : 1.0f;
    const int panel_row0 = pr / (kPanelBatches * L) * (kPanelBatches * L);
    const int nb = std::min(kPanelBatches * L, prows - panel_row0) / L;
    std::int8_t* base = dst + static_cast<std::size_t>(panel_row0) * 4 * groups;
    std::int32_t total = 0;
    for (int c = 0; c < cols; ++c) {
      const double q = std::nearbyint(static_cast<double>(w[c]) / s);
      const int qi = static_cast<int>(std::clamp(q, -127.0, 127.0));
      base[static_cast<std::size_t>(c / 4) * nb * L * 4 + static_cast<std::size_t>(pr - panel_row0) * 4 + c % 4] =
          static_cast<std::int8_t>(qi);
      total += qi;
    }
    scale[pr] = s;
    sum[pr] = total;
  }
}

namespace detail {

// u_j = round(x_j / s_x) + 128 for j < cols, 128 for the padding up to 4 * q8_groups(cols).
// Returns s_x; 0 when x is all zero; NaN when x holds a NaN or an infinity.
inline float quantize_input_q8(const float* x, int cols, std::uint8_t* u) noexcept {
  float amax = 0;
  bool finite = true;
  int j = 0;
#if SPARSEBODY_Q8_AVX512
  __m512 vmax = _mm512_setzero_ps();
  __m512 vbad = _mm512_setzero_ps();  // x - x: 0 for finite values, NaN otherwise
  for (; j + 16 <= cols; j += 16) {
    const __m512 v = _mm512_loadu_ps(x + j);
    vmax = _mm512_max_ps(vmax, _mm512_abs_ps(v));
    vbad = _mm512_add_ps(vbad, _mm512_sub_ps(v, v));
  }
  amax = _mm512_reduce_max_ps(vmax);
  finite = _mm512_cmp_ps_mask(vbad, vbad, _CMP_UNORD_Q) == 0;
#endif
  for (int k = j; k < cols; ++k) {
    finite = finite && std::isfinite(x[k]);
    amax = std::max(amax, std::abs(x[k]));
  }
  if (!finite) return NAN;
  if (amax == 0.0f) return 0.0f;
  const float inv = 127.0f / amax;
  j = 0;
#if SPARSEBODY_Q8_AVX512
  const __m512 vinv = _mm512_set1_ps(inv);
  const __m512i bias = _mm512_set1_epi32(128);
  for (; j + 16 <= cols; j += 16) {
    const __m512i q = _mm512_cvtps_epi32(_mm512_mul_ps(_mm512_loadu_ps(x + j), vinv));  // nearest-even
    _mm_storeu_si128(reinterpret_cast<__m128i*>(u + j), _mm512_cvtepi32_epi8(_mm512_add_epi32(q, bias)));
  }
#endif
  for (; j < cols; ++j) u[j] = static_cast<std::uint8_t>(static_cast<int>(std::nearbyint(x[j] * inv)) + 128);
  for (; j < 4 * q8_groups(cols); ++j) u[j] = 128;
  return amax / 127.0f;
}

// One panel of NB batches: int32 dot products, then y = b + s_r s_x (acc - 128 R_r).
template <int NB>
inline void q8_panel(const std::int8_t* __restrict w, int groups, const std::uint8_t* __restrict u, float sx,
                     const float* __restrict scale, const std::int32_t* __restrict sum, const float* __restrict bias,
                     float* __restrict y) noexcept {
  constexpr int L = kLanes<float>;
#if SPARSEBODY_Q8_AVX512
  if constexpr (L == 16) {
    // vpdpbusd: 5-cycle latency, 1 per cycle: 8 independent accumulators keep it busy.
    constexpr int K = 8 / NB > 1 ? 8 / NB : 1;
    __m512i acc[K][NB];
    for (int k = 0; k < K; ++k)
      for (int b = 0; b < NB; ++b) acc[k][b] = _mm512_setzero_si512();
    std::int32_t u4;
    int g = 0;
    for (; g + K <= groups; g += K) {
      for (int k = 0; k < K; ++k) {
        std::memcpy(&u4, u + 4 * (g + k), 4);
        const __m512i ub = _mm512_set1_epi32(u4);
        const std::int8_t* wg = w + static_cast<std::size_t>(g + k) * NB * 64;
        for (int b = 0; b < NB; ++b)
          acc[k][b] = _mm512_dpbusd_epi32(acc[k][b], ub, _mm512_load_si512(reinterpret_cast<const void*>(wg + b * 64)));
      }
    }
    for (; g < groups; ++g) {
      std::memcpy(&u4, u + 4 * g, 4);
      const __m512i ub = _mm512_set1_epi32(u4);
      const std::int8_t* wg = w + static_cast<std::size_t>(g) * NB * 64;
      for (int b = 0; b < NB; ++b)
        acc[0][b] = _mm512_dpbusd_epi32(acc[0][b], ub, _mm512_load_si512(reinterpret_cast<const void*>(wg + b * 64)));
    }
    const __m512 vsx = _mm512_set1_ps(sx);
    for (int b = 0; b < NB; ++b) {
      __m512i s = acc[0][b];
      for (int k = 1; k < K; ++k) s = _mm512_add_epi32(s, acc[k][b]);
      s = _mm512_sub_epi32(s, _mm512_slli_epi32(_mm512_load_si512(reinterpret_cast<const void*>(sum + b * 16)), 7));
      const __m512 f = _mm512_mul_ps(_mm512_load_ps(scale + b * 16), vsx);
      const __m512 bb = bias ? _mm512_load_ps(bias + b * 16) : _mm512_setzero_ps();
      _mm512_store_ps(y + b * 16, _mm512_fmadd_ps(_mm512_cvtepi32_ps(s), f, bb));
    }
    return;
  }
#endif
  // Portable path: the same integer arithmetic, one row at a time.
  for (int r = 0; r < NB * L; ++r) {
    std::int32_t acc = 0;
    for (int g = 0; g < groups; ++g)
      for (int c = 0; c < 4; ++c)
        acc += static_cast<std::int32_t>(w[static_cast<std::size_t>(g) * NB * L * 4 + r * 4 + c]) * u[4 * g + c];
    acc -= 128 * sum[r];
    y[r] = std::fma(static_cast<float>(acc), scale[r] * sx, bias ? bias[r] : 0.0f);
  }
}

}  // namespace detail

// y[0 .. padded(rows)) = W x + bias with int8 weights (see top). A non-finite x gives NaN outputs
// (so guarded steps see it), an all-zero x gives the bias.
inline void gemv(const PanelMatrix<float, q8>& W, const float* x, const float* bias, float* y) noexcept {
  constexpr int L = kLanes<float>;
  constexpr int P = kPanelBatches * L;
  alignas(64) std::uint8_t u[kQ8MaxCols + 4];
  const float sx = detail::quantize_input_q8(x, W.cols, u);
  const int prows = padded<float>(W.rows);
  if (!(sx > 0.0f)) {  // zero input: y = b; NaN input: NaN
    for (int r = 0; r < prows; ++r) y[r] = sx == 0.0f ? (bias ? bias[r] : 0.0f) : NAN;
    return;
  }
  const int groups = q8_groups(W.cols);
  const std::int8_t* w = W.data;
  int r0 = 0;
  for (; r0 + P <= prows; r0 += P, w += static_cast<std::size_t>(P) * 4 * groups)
    detail::q8_panel<kPanelBatches>(w, groups, u, sx, W.row_scale + r0, W.row_sum + r0, bias ? bias + r0 : nullptr, y + r0);
  const int rest = (prows - r0) / L;
  const float* b = bias ? bias + r0 : nullptr;
  const float* s = W.row_scale + r0;
  const std::int32_t* rs = W.row_sum + r0;
  switch (rest) {
    case 0: break;
    case 1: detail::q8_panel<1>(w, groups, u, sx, s, rs, b, y + r0); break;
    case 2: detail::q8_panel<2>(w, groups, u, sx, s, rs, b, y + r0); break;
    case 3: detail::q8_panel<3>(w, groups, u, sx, s, rs, b, y + r0); break;
    case 4: detail::q8_panel<4>(w, groups, u, sx, s, rs, b, y + r0); break;
    case 5: detail::q8_panel<5>(w, groups, u, sx, s, rs, b, y + r0); break;
    case 6: detail::q8_panel<6>(w, groups, u, sx, s, rs, b, y + r0); break;
    default: detail::q8_panel<7>(w, groups, u, sx, s, rs, b, y + r0); break;
  }
}

}  // namespace sparsebody::nn
