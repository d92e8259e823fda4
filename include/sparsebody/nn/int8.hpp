// int8 weight storage with dynamic activation quantization ("q8"), an opt-in for float networks:
// a quarter of the float bytes per step.
//
// Scheme (the one torch.ao.quantization.quantize_dynamic uses for Linear/GRU, symmetric variant):
//   weights, per output row r, at load:  s_r = max_c |W_rc| / 127,  Q_rc = round(W_rc / s_r) in [-127, 127]
//   input x, per product, at run time:   s_x = max_j |x_j| / 127,   q_j  = round(x_j / s_x)  in [-127, 127]
//   y_r = fma(float(S_r), s_r * s_x, b_r)  with  S_r = sum_j Q_rj q_j  exact in int32
// -128 never occurs on either side (symmetric range); the AVX2 kernel relies on it (see there).
//
// Every kernel computes the same integer S_r and the same final fma, so all of them give the
// portable path's result bit for bit (tests/nn/test_int8_kernels.cpp checks each one a build has):
//   avx512_vnni  vpdpbusd zmm (u8 x s8, 4 products summed into int32): 64 multiply-adds/instruction.
//                It takes unsigned u_j = q_j + 128 and subtracts 128 R_r (R_r = sum_j Q_rj, kept per row).
//   avx_vnni     the same with the VEX ymm form (Alder Lake+, Zen 5): 32 per instruction.
//   avx2         vpmaddubsw(|q_j|, sign(Q_rj, q_j)) then vpmaddwd(., 1): every int16 pair sum is at most
//                2 * 127 * 127 = 32258 < 32767, so the saturating vpmaddubsw never saturates (it would
//                with u_j = q_j + 128: 2 * 255 * 127), and vpsignb never negates -128.
//   neon_dot     vdotq_s32 (ARMv8.2 dot product, s8 x s8, 4 products per int32 lane): 16 per instruction.
//   neon         vmull_s8 + vmlal_s8 (two exact int16 products summed: at most 32258) + vpadalq_s16.
//   portable     the same integer arithmetic in plain C++, one row at a time.
// The build's best kernel (kQ8Kernel) is fixed at compile time from the target macros (no
// -march=native assumption; a generic x86-64 build runs the portable kernel). One run-time upgrade
// on top: a build whose best kernel has no 8-bit dot product (x86-64-v3 AVX2; ARM64 armv8-a NEON,
// the NDK's default) runs on CPUs that have one, so gemv() switches to it when the CPU reports it
// ("Run-time upgrade" below: cpuid / getauxval, read once before main). Same sums, same bits.
//
// Accuracy: each weight keeps ~8 bits relative to its row's largest, each input ~8 bits relative
// to the vector's largest; typical GEMV outputs differ from float by ~1e-3 relative. Measure the
// effect on your task before shipping it (the Neural3Points README section gives ours).
//
// Layout (rows grouped like panel_matrix.hpp: panels of kPanelBatches batches of L = kLanes<float>
// rows): inside a panel, for each group g of 4 columns, NB batches x L rows x 4 bytes, row-major
// within the 4 bytes. Columns are padded to a multiple of 4 with zeros, rows with zero rows.
// Every kernel reads V rows x 4 bytes per vector (V = 16, 8 or 4), so one layout serves all of
// them wherever V divides the panel height (any kernel of a build runs on that build's layout).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "sparsebody/nn/panel_matrix.hpp"

#if defined(__AVX512F__) && defined(__AVX512VNNI__) && defined(__AVX512BW__)
#define SPARSEBODY_Q8_AVX512 1
#endif
#if defined(__AVXVNNI__) && defined(__AVX2__) && defined(__FMA__)
#define SPARSEBODY_Q8_AVXVNNI 1
#endif
#if defined(__AVX2__) && defined(__FMA__)
#define SPARSEBODY_Q8_AVX2 1
#endif
#if defined(__aarch64__) && defined(__ARM_NEON)
#define SPARSEBODY_Q8_NEON 1
#if defined(__ARM_FEATURE_DOTPROD)
#define SPARSEBODY_Q8_NEON_DOT 1
#endif
#endif
#if defined(SPARSEBODY_Q8_AVX512) || defined(SPARSEBODY_Q8_AVX2)
#include <immintrin.h>
#endif
#if defined(SPARSEBODY_Q8_NEON)
#include <arm_neon.h>
#endif
// Run-time upgrades (GCC/Clang function target attributes; define SPARSEBODY_NO_RUNTIME_DISPATCH to
// keep the build's kernel everywhere): an AVX2 build without VNNI on a CPU with AVX-VNNI (Alder
// Lake+, Zen 5) or AVX-512 VNNI + VL (Ice Lake+, Zen 4); an ARM64 build without the dot product on a
// Linux/Android CPU with it (Cortex-A55/A75 and later: every Quest-class headset).
#if !defined(SPARSEBODY_NO_RUNTIME_DISPATCH) && (defined(__GNUC__) || defined(__clang__))
#if defined(SPARSEBODY_Q8_AVX2) && !defined(SPARSEBODY_Q8_AVXVNNI) && !defined(SPARSEBODY_Q8_AVX512) && defined(__x86_64__)
#define SPARSEBODY_Q8_RUNTIME_X86 1
#include <cpuid.h>
#endif
// (Clang declares the dot-product intrinsics for target("dotprod") functions from version 17 on;
// older Clang only under -march=...+dotprod.)
#if defined(SPARSEBODY_Q8_NEON) && !defined(SPARSEBODY_Q8_NEON_DOT) && defined(__linux__) && \
    (!defined(__clang__) || __clang_major__ >= 17)
#define SPARSEBODY_Q8_RUNTIME_ARM 1
#include <sys/auxv.h>
#endif
#endif
#include <cstdlib>

namespace sparsebody::nn {

struct q8 {
  std::int8_t value = 0;
};

// Longest input a q8 product takes (its quantized copy lives on the stack: no allocation).
inline constexpr int kQ8MaxCols = 4096;

constexpr int q8_groups(int cols) { return (cols + 3) / 4; }

enum class Q8Kernel { portable, avx2, avx_vnni, avx512_vnni, neon, neon_dot };

// Rows one vector of the kernel covers; the kernel runs on a build's layout when it divides the
// lane count L (every panel height is a multiple of L).
constexpr int q8_kernel_rows(Q8Kernel k) {
  switch (k) {
    case Q8Kernel::avx512_vnni: return 16;
    case Q8Kernel::avx2:
    case Q8Kernel::avx_vnni: return 8;
    case Q8Kernel::neon:
    case Q8Kernel::neon_dot: return 4;
    default: return 1;
  }
}

// Whether kernel k is compiled into this build and can run on its layout.
constexpr bool q8_kernel_available(Q8Kernel k) {
  if (kLanes<float> % q8_kernel_rows(k) != 0) return false;
  switch (k) {
    case Q8Kernel::portable: return true;
#if SPARSEBODY_Q8_AVX512
    case Q8Kernel::avx512_vnni: return true;
#endif
#if SPARSEBODY_Q8_AVXVNNI
    case Q8Kernel::avx_vnni: return true;
#endif
#if SPARSEBODY_Q8_AVX2
    case Q8Kernel::avx2: return true;
#endif
#if SPARSEBODY_Q8_NEON
    case Q8Kernel::neon: return true;
#endif
#if SPARSEBODY_Q8_NEON_DOT
    case Q8Kernel::neon_dot: return true;
#endif
    default: return false;
  }
}

// The kernel gemv() uses in this build: the widest available.
inline constexpr Q8Kernel kQ8Kernel =
    q8_kernel_available(Q8Kernel::avx512_vnni) ? Q8Kernel::avx512_vnni
    : q8_kernel_available(Q8Kernel::avx_vnni)  ? Q8Kernel::avx_vnni
    : q8_kernel_available(Q8Kernel::avx2)      ? Q8Kernel::avx2
    : q8_kernel_available(Q8Kernel::neon_dot)  ? Q8Kernel::neon_dot
    : q8_kernel_available(Q8Kernel::neon)      ? Q8Kernel::neon
                                               : Q8Kernel::portable;

constexpr const char* q8_kernel_name(Q8Kernel k) {
  switch (k) {
    case Q8Kernel::avx512_vnni: return "AVX-512 VNNI";
    case Q8Kernel::avx_vnni: return "AVX-VNNI";
    case Q8Kernel::avx2: return "AVX2";
    case Q8Kernel::neon_dot: return "NEON dot product";
    case Q8Kernel::neon: return "NEON";
    default: return "portable";
  }
}

template <>
struct PanelMatrix<float, q8> {
  const std::int8_t* data = nullptr;     // Q, panel layout above
  const float* row_scale = nullptr;      // s_r, padded rows (padding 0)
  const std::int32_t* row_sum = nullptr; // R_r = sum_c Q_rc, padded rows (for the VNNI kernels)
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
      const int qi = static_cast<int>(std::clamp(q, -127.0, 127.0));  // symmetric: never -128
      base[static_cast<std::size_t>(c / 4) * nb * L * 4 + static_cast<std::size_t>(pr - panel_row0) * 4 + c % 4] =
          static_cast<std::int8_t>(qi);
      total += qi;
    }
    scale[pr] = s;
    sum[pr] = total;
  }
}

namespace detail {

// Input quantization: q_j = round(x_j / s_x) (ties to even, as the scheme's nearbyint) for j < cols,
// 0 for the padding up to 4 * q8_groups(cols). Returns s_x; 0 when x is all zero; NaN when x holds
// a NaN or an infinity. The SIMD loops compute the same floats (amax is order-independent, then
// the same scalar inv = 127 / amax and one rounding of x_j * inv), so they give the scalar result.
template <bool kSimd = true>
inline float quantize_input_q8(const float* x, int cols, std::int8_t* q) noexcept {
  float amax = 0;
  bool finite = true;
  int j = 0;
  if constexpr (kSimd) {
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
#elif SPARSEBODY_Q8_AVX2
    const __m256 absmask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
    __m256 vmax = _mm256_setzero_ps();
    __m256 vbad = _mm256_setzero_ps();
    for (; j + 8 <= cols; j += 8) {
      const __m256 v = _mm256_loadu_ps(x + j);
      vmax = _mm256_max_ps(vmax, _mm256_and_ps(v, absmask));
      vbad = _mm256_add_ps(vbad, _mm256_sub_ps(v, v));
    }
    alignas(32) float lanes[8];
    _mm256_store_ps(lanes, vmax);
    for (float v : lanes) amax = std::max(amax, v);
    finite = _mm256_movemask_ps(_mm256_cmp_ps(vbad, vbad, _CMP_UNORD_Q)) == 0;
#elif SPARSEBODY_Q8_NEON
    float32x4_t vmax = vdupq_n_f32(0.f);
    float32x4_t vbad = vdupq_n_f32(0.f);
    for (; j + 4 <= cols; j += 4) {
      const float32x4_t v = vld1q_f32(x + j);
      vmax = vmaxq_f32(vmax, vabsq_f32(v));
      vbad = vaddq_f32(vbad, vsubq_f32(v, v));
    }
    amax = vmaxvq_f32(vmax);
    finite = vminvq_u32(vceqq_f32(vbad, vbad)) != 0;  // NaN != NaN
#endif
  }
  for (int k = j; k < cols; ++k) {
    finite = finite && std::isfinite(x[k]);
    amax = std::max(amax, std::abs(x[k]));
  }
  if (!finite) return NAN;
  if (amax == 0.0f) return 0.0f;
  const float inv = 127.0f / amax;
  j = 0;
  if constexpr (kSimd) {
#if SPARSEBODY_Q8_AVX512
    const __m512 vinv = _mm512_set1_ps(inv);
    for (; j + 16 <= cols; j += 16) {
      const __m512i v = _mm512_cvtps_epi32(_mm512_mul_ps(_mm512_loadu_ps(x + j), vinv));  // nearest-even
      _mm_storeu_si128(reinterpret_cast<__m128i*>(q + j), _mm512_cvtepi32_epi8(v));
    }
#elif SPARSEBODY_Q8_AVX2
    const __m256 vinv = _mm256_set1_ps(inv);
    for (; j + 8 <= cols; j += 8) {
      const __m256i v = _mm256_cvtps_epi32(_mm256_mul_ps(_mm256_loadu_ps(x + j), vinv));  // nearest-even
      const __m256i h = _mm256_packs_epi32(v, v);  // per 128-bit half: its 4 values as int16, twice
      const __m256i b = _mm256_packs_epi16(h, h);  // ... as bytes, the first 4 are the half's values
      const std::int32_t lo = _mm_cvtsi128_si32(_mm256_castsi256_si128(b));
      const std::int32_t hi = _mm_cvtsi128_si32(_mm256_extracti128_si256(b, 1));
      std::memcpy(q + j, &lo, 4);
      std::memcpy(q + j + 4, &hi, 4);
    }
#elif SPARSEBODY_Q8_NEON
    const float32x4_t vinv = vdupq_n_f32(inv);
    for (; j + 8 <= cols; j += 8) {
      const int32x4_t a = vcvtnq_s32_f32(vmulq_f32(vld1q_f32(x + j), vinv));  // nearest-even
      const int32x4_t b = vcvtnq_s32_f32(vmulq_f32(vld1q_f32(x + j + 4), vinv));
      vst1_s8(q + j, vmovn_s16(vcombine_s16(vmovn_s32(a), vmovn_s32(b))));
    }
#endif
  }
  for (; j < cols; ++j) q[j] = static_cast<std::int8_t>(static_cast<int>(std::nearbyint(x[j] * inv)));
  for (; j < 4 * q8_groups(cols); ++j) q[j] = 0;
  return amax / 127.0f;
}

// The 4 input bytes of column group g as one 32-bit word (each kernel broadcasts it).
inline std::int32_t q8_group_word(const std::int8_t* q, int g) noexcept {
  std::int32_t v;
  std::memcpy(&v, q + 4 * g, 4);
  return v;
}

// The dot-product panel kernels (u8 x s8 vpdpbusd on ymm, s8 x s8 sdot): each a function compiled for
// its feature by a target attribute, so that the build whose target has it (q8_panel) and a build
// that only finds it at run time ("Run-time upgrade" below) run the same code. No lambdas inside: a
// lambda's body would not inherit the attribute. They compute q8_panel's arithmetic (u_j = q_j + 128
// against Q, minus 128 R_r for vpdpbusd; the accumulator sets and the epilogue of the other kernels),
// so the same bits, on the build's layout (8 rows (x86) or 4 (ARM) per vector divide its lanes).
#if defined(__GNUC__) || defined(__clang__)
#define SPARSEBODY_Q8_TARGET(T) __attribute__((target(T)))
#else
#define SPARSEBODY_Q8_TARGET(T)
#endif
#define SPARSEBODY_Q8_PANEL_ARGS                                                                                  \
  const std::int8_t *__restrict w, int groups, const std::int8_t *__restrict q, float sx,                        \
      const float *__restrict scale, const std::int32_t *__restrict sum, const float *__restrict bias,           \
      float *__restrict y
// The batched kernels' arguments: M instances' quantized inputs, scales and outputs (full panels only).
#define SPARSEBODY_Q8_BATCH_ARGS                                                                                  \
  const std::int8_t *__restrict w, int groups, const std::int8_t *const *q, const float *sx,                    \
      const float *__restrict scale, const std::int32_t *__restrict sum, const float *__restrict bias,           \
      float *const *y
#if SPARSEBODY_Q8_AVXVNNI || SPARSEBODY_Q8_RUNTIME_X86
// 256-bit vpdpbusd: VEX (AVX-VNNI: the -mavxvnni build's kernel and the upgrade) or EVEX (AVX-512
// VNNI + VL: the upgrade only), one function per target.
#define SPARSEBODY_Q8_VNNI256_PANEL(NAME, TARGET, DPBUSD)                                                         \
  template <int NB>                                                                                               \
  SPARSEBODY_Q8_TARGET(TARGET) inline void NAME(SPARSEBODY_Q8_PANEL_ARGS) noexcept {                          \
    constexpr int R = NB * kLanes<float>;                                                                         \
    constexpr int NV = R / 8;                                                                                     \
    constexpr int K = 8 / NV > 1 ? 8 / NV : 1;                                                                    \
    __m256i acc[K][NV];                                                                                           \
    for (int k = 0; k < K; ++k)                                                                                   \
      for (int b = 0; b < NV; ++b) acc[k][b] = _mm256_setzero_si256();                                            \
    int g = 0;                                                                                                    \
    for (; g + K <= groups; g += K)                                                                               \
      for (int k = 0; k < K; ++k) {                                                                               \
        const __m256i ub = _mm256_set1_epi32(q8_group_word(q, g + k) ^ static_cast<std::int32_t>(0x80808080u));   \
        const std::int8_t* wg = w + static_cast<std::size_t>(g + k) * R * 4;                                       \
        for (int b = 0; b < NV; ++b)                                                                              \
          acc[k][b] = DPBUSD(acc[k][b], ub, _mm256_load_si256(reinterpret_cast<const __m256i*>(wg + b * 32)));    \
      }                                                                                                           \
    for (; g < groups; ++g) {                                                                                     \
      const __m256i ub = _mm256_set1_epi32(q8_group_word(q, g) ^ static_cast<std::int32_t>(0x80808080u));         \
      const std::int8_t* wg = w + static_cast<std::size_t>(g) * R * 4;                                             \
      for (int b = 0; b < NV; ++b)                                                                                \
        acc[0][b] = DPBUSD(acc[0][b], ub, _mm256_load_si256(reinterpret_cast<const __m256i*>(wg + b * 32)));      \
    }                                                                                                             \
    const __m256 vsx = _mm256_set1_ps(sx);                                                                        \
    for (int b = 0; b < NV; ++b) {                                                                                \
      __m256i s = acc[0][b];                                                                                      \
      for (int k = 1; k < K; ++k) s = _mm256_add_epi32(s, acc[k][b]);                                             \
      s = _mm256_sub_epi32(s, _mm256_slli_epi32(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(sum + b * 8)), 7)); \
      const __m256 f = _mm256_mul_ps(_mm256_loadu_ps(scale + b * 8), vsx);                                        \
      const __m256 bb = bias ? _mm256_loadu_ps(bias + b * 8) : _mm256_setzero_ps();                               \
      _mm256_storeu_ps(y + b * 8, _mm256_fmadd_ps(_mm256_cvtepi32_ps(s), f, bb));                                 \
    }                                                                                                             \
  }
// M instances through one full panel (NV vectors of 8 rows), in sub-blocks of 4 vectors: each weight
// vector is loaded once per column group and multiplied with every instance's input word (M x 4
// accumulators in registers: M = 3 fills the 16 ymm of VEX code, 4 fits the 32 of EVEX). Exact int32 sums and
// the epilogue above: every instance gets its own single-panel result bit for bit.
#define SPARSEBODY_Q8_VNNI256_BATCH(NAME, TARGET, DPBUSD)                                                         \
  template <int M>                                                                                                \
  SPARSEBODY_Q8_TARGET(TARGET) inline void NAME(SPARSEBODY_Q8_BATCH_ARGS) noexcept {                           \
    constexpr int R = kPanelBatches * kLanes<float>;                                                              \
    constexpr int NV = R / 8, NVB = 4;                                                                            \
    static_assert(NV % NVB == 0, "panel vectors must split into sub-blocks of 4");                                \
    const std::int8_t* qq[M];                                                                                     \
    for (int m = 0; m < M; ++m) qq[m] = q[m];                                                                     \
    for (int b0 = 0; b0 < NV; b0 += NVB) {                                                                        \
      __m256i acc[M][NVB];                                                                                        \
      for (int m = 0; m < M; ++m)                                                                                 \
        for (int b = 0; b < NVB; ++b) acc[m][b] = _mm256_setzero_si256();                                         \
      for (int g = 0; g < groups; ++g) {                                                                          \
        __m256i ub[M];                                                                                            \
        for (int m = 0; m < M; ++m)                                                                               \
          ub[m] = _mm256_set1_epi32(q8_group_word(qq[m], g) ^ static_cast<std::int32_t>(0x80808080u));            \
        const std::int8_t* wg = w + static_cast<std::size_t>(g) * R * 4 + b0 * 32;                                \
        for (int b = 0; b < NVB; ++b) {                                                                           \
          const __m256i wv = _mm256_load_si256(reinterpret_cast<const __m256i*>(wg + b * 32));                    \
          for (int m = 0; m < M; ++m) acc[m][b] = DPBUSD(acc[m][b], ub[m], wv);                                   \
        }                                                                                                         \
      }                                                                                                           \
      for (int b = 0; b < NVB; ++b) {                                                                             \
        const int r = (b0 + b) * 8;                                                                               \
        const __m256i rs = _mm256_slli_epi32(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(sum + r)), 7);  \
        const __m256 sc = _mm256_loadu_ps(scale + r);                                                             \
        const __m256 bb = bias ? _mm256_loadu_ps(bias + r) : _mm256_setzero_ps();                                 \
        for (int m = 0; m < M; ++m) {                                                                             \
          const __m256 f = _mm256_mul_ps(sc, _mm256_set1_ps(sx[m]));                                              \
          _mm256_storeu_ps(y[m] + r, _mm256_fmadd_ps(_mm256_cvtepi32_ps(_mm256_sub_epi32(acc[m][b], rs)), f, bb)); \
        }                                                                                                         \
      }                                                                                                           \
    }                                                                                                             \
  }
SPARSEBODY_Q8_VNNI256_PANEL(q8_panel_vnni256_vex, "avx2,fma,avxvnni", _mm256_dpbusd_avx_epi32)
SPARSEBODY_Q8_VNNI256_BATCH(q8_panel_batch_vnni256_vex, "avx2,fma,avxvnni", _mm256_dpbusd_avx_epi32)
#if SPARSEBODY_Q8_RUNTIME_X86
SPARSEBODY_Q8_VNNI256_PANEL(q8_panel_vnni256_evex, "avx2,fma,avx512f,avx512vl,avx512vnni", _mm256_dpbusd_epi32)
SPARSEBODY_Q8_VNNI256_BATCH(q8_panel_batch_vnni256_evex, "avx2,fma,avx512f,avx512vl,avx512vnni", _mm256_dpbusd_epi32)
#endif
#undef SPARSEBODY_Q8_VNNI256_PANEL
#undef SPARSEBODY_Q8_VNNI256_BATCH
#endif
#if SPARSEBODY_Q8_NEON_DOT || SPARSEBODY_Q8_RUNTIME_ARM
// vdotq_s32 (s8 x s8): the armv8.2-a+dotprod build's kernel and the upgrade. GCC's arm_neon.h declares it for
// armv8.2-a+dotprod, Clang's for the "dotprod" feature.
#if defined(__clang__)
#define SPARSEBODY_Q8_DOTPROD_TARGET "dotprod"
#else
#define SPARSEBODY_Q8_DOTPROD_TARGET "arch=armv8.2-a+dotprod"
#endif
template <int NB>
SPARSEBODY_Q8_TARGET(SPARSEBODY_Q8_DOTPROD_TARGET) inline void q8_panel_sdot(SPARSEBODY_Q8_PANEL_ARGS) noexcept {
  constexpr int R = NB * kLanes<float>;
  constexpr int NV = R / 4;
  constexpr int K = 8 / NV > 1 ? 8 / NV : 1;
  (void)sum;
  int32x4_t acc[K][NV];
  for (int k = 0; k < K; ++k)
    for (int b = 0; b < NV; ++b) acc[k][b] = vdupq_n_s32(0);
  int g = 0;
  for (; g + K <= groups; g += K)
    for (int k = 0; k < K; ++k) {
      const int8x16_t qb = vreinterpretq_s8_s32(vdupq_n_s32(q8_group_word(q, g + k)));
      const std::int8_t* wg = w + static_cast<std::size_t>(g + k) * R * 4;
      for (int b = 0; b < NV; ++b) acc[k][b] = vdotq_s32(acc[k][b], vld1q_s8(wg + b * 16), qb);
    }
  for (; g < groups; ++g) {
    const int8x16_t qb = vreinterpretq_s8_s32(vdupq_n_s32(q8_group_word(q, g)));
    const std::int8_t* wg = w + static_cast<std::size_t>(g) * R * 4;
    for (int b = 0; b < NV; ++b) acc[0][b] = vdotq_s32(acc[0][b], vld1q_s8(wg + b * 16), qb);
  }
  const float32x4_t vsx = vdupq_n_f32(sx);
  for (int b = 0; b < NV; ++b) {
    int32x4_t s = acc[0][b];
    for (int k = 1; k < K; ++k) s = vaddq_s32(s, acc[k][b]);
    const float32x4_t f = vmulq_f32(vld1q_f32(scale + b * 4), vsx);
    const float32x4_t bb = bias ? vld1q_f32(bias + b * 4) : vdupq_n_f32(0.f);
    vst1q_f32(y + b * 4, vfmaq_f32(bb, vcvtq_f32_s32(s), f));
  }
}
// M instances through one full panel (NV vectors of 4 rows) in sub-blocks of 4 vectors, each weight
// vector loaded once per column group for all M (M x 4 of the 32 q registers), as the VNNI batch.
template <int M>
SPARSEBODY_Q8_TARGET(SPARSEBODY_Q8_DOTPROD_TARGET) inline void q8_panel_batch_sdot(SPARSEBODY_Q8_BATCH_ARGS) noexcept {
  constexpr int R = kPanelBatches * kLanes<float>;
  constexpr int NV = R / 4, NVB = 4;
  static_assert(NV % NVB == 0, "panel vectors must split into sub-blocks of 4");
  (void)sum;
  const std::int8_t* qq[M];
  for (int m = 0; m < M; ++m) qq[m] = q[m];
  for (int b0 = 0; b0 < NV; b0 += NVB) {
    int32x4_t acc[M][NVB];
    for (int m = 0; m < M; ++m)
      for (int b = 0; b < NVB; ++b) acc[m][b] = vdupq_n_s32(0);
    for (int g = 0; g < groups; ++g) {
      int8x16_t qb[M];
      for (int m = 0; m < M; ++m) qb[m] = vreinterpretq_s8_s32(vdupq_n_s32(q8_group_word(qq[m], g)));
      const std::int8_t* wg = w + static_cast<std::size_t>(g) * R * 4 + b0 * 16;
      for (int b = 0; b < NVB; ++b) {
        const int8x16_t wv = vld1q_s8(wg + b * 16);
        for (int m = 0; m < M; ++m) acc[m][b] = vdotq_s32(acc[m][b], wv, qb[m]);
      }
    }
    for (int b = 0; b < NVB; ++b) {
      const int r = (b0 + b) * 4;
      const float32x4_t sc = vld1q_f32(scale + r);
      const float32x4_t bb = bias ? vld1q_f32(bias + r) : vdupq_n_f32(0.f);
      for (int m = 0; m < M; ++m) {
        const float32x4_t f = vmulq_f32(sc, vdupq_n_f32(sx[m]));
        vst1q_f32(y[m] + r, vfmaq_f32(bb, vcvtq_f32_s32(acc[m][b]), f));
      }
    }
  }
}
#undef SPARSEBODY_Q8_DOTPROD_TARGET
#endif

// One panel of R = NB * L rows with kernel K: S_r (exact int32), then y_r = fma(S_r, s_r s_x, b_r).
// w advances NB * L * 4 bytes per column group. Multi-chain kernels split the groups over K
// accumulator sets (a latency of 3-5 cycles per multiply-add instruction needs >= 8 in flight).
template <Q8Kernel Kern, int NB>
inline void q8_panel(const std::int8_t* __restrict w, int groups, const std::int8_t* __restrict q, float sx,
                     const float* __restrict scale, const std::int32_t* __restrict sum, const float* __restrict bias,
                     float* __restrict y) noexcept {
  constexpr int R = NB * kLanes<float>;
  static_assert(q8_kernel_available(Kern), "q8 kernel not compiled into this build");
  [[maybe_unused]] constexpr int NV = R / q8_kernel_rows(Kern);  // vectors per column group
  [[maybe_unused]] constexpr int K = 8 / NV > 1 ? 8 / NV : 1;   // accumulator sets
  (void)sum;  // only the VNNI kernels (unsigned inputs) need the row sums
#if SPARSEBODY_Q8_AVX512
  if constexpr (Kern == Q8Kernel::avx512_vnni) {
    __m512i acc[K][NV];
    for (int k = 0; k < K; ++k)
      for (int b = 0; b < NV; ++b) acc[k][b] = _mm512_setzero_si512();
    auto step = [&](int k, int g) {
      const __m512i ub = _mm512_set1_epi32(q8_group_word(q, g) ^ static_cast<std::int32_t>(0x80808080u));  // u = q + 128
      const std::int8_t* wg = w + static_cast<std::size_t>(g) * R * 4;
      for (int b = 0; b < NV; ++b)
        acc[k][b] = _mm512_dpbusd_epi32(acc[k][b], ub, _mm512_load_si512(reinterpret_cast<const void*>(wg + b * 64)));
    };
    int g = 0;
    for (; g + K <= groups; g += K)
      for (int k = 0; k < K; ++k) step(k, g + k);
    for (; g < groups; ++g) step(0, g);
    const __m512 vsx = _mm512_set1_ps(sx);
    for (int b = 0; b < NV; ++b) {
      __m512i s = acc[0][b];
      for (int k = 1; k < K; ++k) s = _mm512_add_epi32(s, acc[k][b]);
      s = _mm512_sub_epi32(s, _mm512_slli_epi32(_mm512_loadu_si512(reinterpret_cast<const void*>(sum + b * 16)), 7));
      const __m512 f = _mm512_mul_ps(_mm512_loadu_ps(scale + b * 16), vsx);
      const __m512 bb = bias ? _mm512_loadu_ps(bias + b * 16) : _mm512_setzero_ps();
      _mm512_storeu_ps(y + b * 16, _mm512_fmadd_ps(_mm512_cvtepi32_ps(s), f, bb));
    }
    return;
  }
#endif
#if SPARSEBODY_Q8_AVXVNNI
  if constexpr (Kern == Q8Kernel::avx_vnni) {
    q8_panel_vnni256_vex<NB>(w, groups, q, sx, scale, sum, bias, y);
    return;
  }
#endif
#if SPARSEBODY_Q8_AVX2
  if constexpr (Kern == Q8Kernel::avx2) {
    __m256i acc[K][NV];
    for (int k = 0; k < K; ++k)
      for (int b = 0; b < NV; ++b) acc[k][b] = _mm256_setzero_si256();
    const __m256i ones = _mm256_set1_epi16(1);
    auto step = [&](int k, int g) {
      const std::int8_t* wg = w + static_cast<std::size_t>(g) * R * 4;
      const __m256i qb = _mm256_set1_epi32(q8_group_word(q, g));
      const __m256i qa = _mm256_abs_epi8(qb);  // |q| as unsigned bytes (<= 127)
      for (int b = 0; b < NV; ++b) {
        const __m256i ws = _mm256_sign_epi8(_mm256_load_si256(reinterpret_cast<const __m256i*>(wg + b * 32)), qb);
        acc[k][b] = _mm256_add_epi32(acc[k][b], _mm256_madd_epi16(_mm256_maddubs_epi16(qa, ws), ones));
      }
    };
    int g = 0;
    for (; g + K <= groups; g += K)
      for (int k = 0; k < K; ++k) step(k, g + k);
    for (; g < groups; ++g) step(0, g);
    const __m256 vsx = _mm256_set1_ps(sx);
    for (int b = 0; b < NV; ++b) {
      __m256i s = acc[0][b];
      for (int k = 1; k < K; ++k) s = _mm256_add_epi32(s, acc[k][b]);
      const __m256 f = _mm256_mul_ps(_mm256_loadu_ps(scale + b * 8), vsx);
      const __m256 bb = bias ? _mm256_loadu_ps(bias + b * 8) : _mm256_setzero_ps();
      _mm256_storeu_ps(y + b * 8, _mm256_fmadd_ps(_mm256_cvtepi32_ps(s), f, bb));
    }
    return;
  }
#endif
#if SPARSEBODY_Q8_NEON_DOT
  if constexpr (Kern == Q8Kernel::neon_dot) {
    q8_panel_sdot<NB>(w, groups, q, sx, scale, sum, bias, y);
    return;
  }
#endif
#if SPARSEBODY_Q8_NEON
  if constexpr (Kern == Q8Kernel::neon) {
    // Per vector (rows 0-3 x 4 columns), lo/hi: rows 0-1 / 2-3, each int32 lane half a row;
    // two groups' int16 products are summed before widening (|sum| <= 2 * 127 * 127).
    int32x4_t lo[NV], hi[NV];
    for (int b = 0; b < NV; ++b) lo[b] = hi[b] = vdupq_n_s32(0);
    int g = 0;
    for (; g + 2 <= groups; g += 2) {
      const int8x16_t q0 = vreinterpretq_s8_s32(vdupq_n_s32(q8_group_word(q, g)));
      const int8x16_t q1 = vreinterpretq_s8_s32(vdupq_n_s32(q8_group_word(q, g + 1)));
      const std::int8_t* w0 = w + static_cast<std::size_t>(g) * R * 4;
      const std::int8_t* w1 = w0 + R * 4;
      for (int b = 0; b < NV; ++b) {
        const int8x16_t a = vld1q_s8(w0 + b * 16), c = vld1q_s8(w1 + b * 16);
        lo[b] = vpadalq_s16(lo[b], vmlal_s8(vmull_s8(vget_low_s8(a), vget_low_s8(q0)), vget_low_s8(c), vget_low_s8(q1)));
        hi[b] = vpadalq_s16(hi[b], vmlal_high_s8(vmull_high_s8(a, q0), c, q1));
      }
    }
    for (; g < groups; ++g) {
      const int8x16_t q0 = vreinterpretq_s8_s32(vdupq_n_s32(q8_group_word(q, g)));
      const std::int8_t* w0 = w + static_cast<std::size_t>(g) * R * 4;
      for (int b = 0; b < NV; ++b) {
        const int8x16_t a = vld1q_s8(w0 + b * 16);
        lo[b] = vpadalq_s16(lo[b], vmull_s8(vget_low_s8(a), vget_low_s8(q0)));
        hi[b] = vpadalq_s16(hi[b], vmull_high_s8(a, q0));
      }
    }
    int32x4_t sums[NV];
    for (int b = 0; b < NV; ++b) sums[b] = vpaddq_s32(lo[b], hi[b]);  // [r0, r1, r2, r3]
    const float32x4_t vsx = vdupq_n_f32(sx);
    for (int b = 0; b < NV; ++b) {
      const float32x4_t f = vmulq_f32(vld1q_f32(scale + b * 4), vsx);
      const float32x4_t bb = bias ? vld1q_f32(bias + b * 4) : vdupq_n_f32(0.f);
      vst1q_f32(y + b * 4, vfmaq_f32(bb, vcvtq_f32_s32(sums[b]), f));
    }
    return;
  }
#endif
  // Portable path: the same integer arithmetic, one row at a time.
  for (int r = 0; r < R; ++r) {
    std::int32_t acc = 0;
    for (int g = 0; g < groups; ++g)
      for (int c = 0; c < 4; ++c)
        acc += static_cast<std::int32_t>(w[static_cast<std::size_t>(g) * R * 4 + r * 4 + c]) * q[4 * g + c];
    y[r] = std::fma(static_cast<float>(acc), scale[r] * sx, bias ? bias[r] : 0.0f);
  }
}

// M instances through one full panel (NB = kPanelBatches, R = NB * L rows) with a dot-product
// kernel: each weight vector is loaded once per column group and multiplied with every instance's
// input word, in sub-blocks of NVB vectors (M x NVB accumulators stay in registers). The int32 sums
// are exact, and the epilogue is q8_panel's, so every instance's outputs equal its own q8_panel call
// bit for bit. AVX-512 VNNI: 4 instances on zmm; AVX-VNNI: 3 on ymm (16 registers); dot product: 4.
template <Q8Kernel Kern> constexpr int q8_batch_instances() {
  return Kern == Q8Kernel::avx512_vnni || Kern == Q8Kernel::neon_dot ? 4 : Kern == Q8Kernel::avx_vnni ? 3 : 1;
}
template <Q8Kernel Kern> constexpr bool q8_batch_kernel() {
#if SPARSEBODY_Q8_AVX512
  if (Kern == Q8Kernel::avx512_vnni) return true;
#endif
#if SPARSEBODY_Q8_AVXVNNI
  if (Kern == Q8Kernel::avx_vnni) return true;
#endif
#if SPARSEBODY_Q8_NEON_DOT
  if (Kern == Q8Kernel::neon_dot) return true;
#endif
  return false;
}
template <Q8Kernel Kern, int M>
inline void q8_panel_batch(SPARSEBODY_Q8_BATCH_ARGS) noexcept {
  constexpr int R = kPanelBatches * kLanes<float>;
  [[maybe_unused]] constexpr int V = q8_kernel_rows(Kern);  // rows per vector
  [[maybe_unused]] constexpr int NV = R / V;
  [[maybe_unused]] constexpr int NVB = 4;
  [[maybe_unused]] const std::int8_t* qq[M];
  for (int m = 0; m < M; ++m) qq[m] = q[m];
#if SPARSEBODY_Q8_AVX512
  if constexpr (Kern == Q8Kernel::avx512_vnni) {
    for (int b0 = 0; b0 < NV; b0 += NVB) {
      __m512i acc[M][NVB];
      for (int m = 0; m < M; ++m)
        for (int b = 0; b < NVB; ++b) acc[m][b] = _mm512_setzero_si512();
      for (int g = 0; g < groups; ++g) {
        __m512i ub[M];
        for (int m = 0; m < M; ++m) ub[m] = _mm512_set1_epi32(q8_group_word(qq[m], g) ^ static_cast<std::int32_t>(0x80808080u));
        const std::int8_t* wg = w + static_cast<std::size_t>(g) * R * 4 + b0 * 64;
        for (int b = 0; b < NVB; ++b) {
          const __m512i wv = _mm512_load_si512(reinterpret_cast<const void*>(wg + b * 64));
          for (int m = 0; m < M; ++m) acc[m][b] = _mm512_dpbusd_epi32(acc[m][b], ub[m], wv);
        }
      }
      for (int b = 0; b < NVB; ++b) {
        const int r = (b0 + b) * 16;
        const __m512i rs = _mm512_slli_epi32(_mm512_loadu_si512(reinterpret_cast<const void*>(sum + r)), 7);
        const __m512 sc = _mm512_loadu_ps(scale + r);
        const __m512 bb = bias ? _mm512_loadu_ps(bias + r) : _mm512_setzero_ps();
        for (int m = 0; m < M; ++m) {
          const __m512i s = _mm512_sub_epi32(acc[m][b], rs);
          const __m512 f = _mm512_mul_ps(sc, _mm512_set1_ps(sx[m]));
          _mm512_storeu_ps(y[m] + r, _mm512_fmadd_ps(_mm512_cvtepi32_ps(s), f, bb));
        }
      }
    }
    return;
  }
#endif
#if SPARSEBODY_Q8_AVXVNNI
  if constexpr (Kern == Q8Kernel::avx_vnni) {
    q8_panel_batch_vnni256_vex<M>(w, groups, q, sx, scale, sum, bias, y);
    return;
  }
#endif
#if SPARSEBODY_Q8_NEON_DOT
  if constexpr (Kern == Q8Kernel::neon_dot) {
    q8_panel_batch_sdot<M>(w, groups, q, sx, scale, sum, bias, y);
    return;
  }
#endif
  for (int m = 0; m < M; ++m) q8_panel<Kern, kPanelBatches>(w, groups, q[m], sx[m], scale, sum, bias, y[m]);
}

// The panels of one quantized input (gemv_q8 after the quantization): full panels of
// kPanelBatches batches from row `from` on, then the tail batches. Panel::run<NB> does one panel.
template <class Panel>
inline void q8_panels_with(const PanelMatrix<float, q8>& W, const std::int8_t* q, float sx, const float* bias, float* y,
                           int from = 0) noexcept {
  constexpr int L = kLanes<float>;
  constexpr int P = kPanelBatches * L;
  const int prows = padded<float>(W.rows);
  const int groups = q8_groups(W.cols);
  const std::int8_t* w = W.data + static_cast<std::size_t>(from) * 4 * groups;
  int r0 = from;
  for (; r0 + P <= prows; r0 += P, w += static_cast<std::size_t>(P) * 4 * groups)
    Panel::template run<kPanelBatches>(w, groups, q, sx, W.row_scale + r0, W.row_sum + r0, bias ? bias + r0 : nullptr, y + r0);
  const int rest = (prows - r0) / L;
  const float* b = bias ? bias + r0 : nullptr;
  const float* s = W.row_scale + r0;
  const std::int32_t* rs = W.row_sum + r0;
  switch (rest) {  // compile-time batch counts keep the accumulators in registers
    case 0: break;
    case 1: Panel::template run<1>(w, groups, q, sx, s, rs, b, y + r0); break;
    case 2: Panel::template run<2>(w, groups, q, sx, s, rs, b, y + r0); break;
    case 3: Panel::template run<3>(w, groups, q, sx, s, rs, b, y + r0); break;
    case 4: Panel::template run<4>(w, groups, q, sx, s, rs, b, y + r0); break;
    case 5: Panel::template run<5>(w, groups, q, sx, s, rs, b, y + r0); break;
    case 6: Panel::template run<6>(w, groups, q, sx, s, rs, b, y + r0); break;
    default: Panel::template run<7>(w, groups, q, sx, s, rs, b, y + r0); break;
  }
}

template <Q8Kernel Kern>
struct BuildPanel {  // the build's kernel Kern
  template <int NB> static void run(SPARSEBODY_Q8_PANEL_ARGS) noexcept { q8_panel<Kern, NB>(w, groups, q, sx, scale, sum, bias, y); }
};
template <Q8Kernel Kern>
struct BuildBatchPanel {  // M instances per weight load with the build's kernel (M = 1: none, one product each)
  static constexpr int M = q8_batch_kernel<Kern>() ? q8_batch_instances<Kern>() : 1;
  static void run(SPARSEBODY_Q8_BATCH_ARGS) noexcept { q8_panel_batch<Kern, M>(w, groups, q, sx, scale, sum, bias, y); }
};
template <Q8Kernel Kern>
inline void q8_panels(const PanelMatrix<float, q8>& W, const std::int8_t* q, float sx, const float* bias, float* y,
                      int from = 0) noexcept {
  q8_panels_with<BuildPanel<Kern>>(W, q, sx, bias, y, from);
}

// ---- Run-time upgrade ----------------------------------------------------------------------------
// The upgrades run the dot-product panel kernels above (q8_panel_vnni256_vex / _evex, q8_panel_sdot),
// which a build targeting the feature runs through q8_panel: the same code, the same bits.
enum class Q8Upgrade { none, avx_vnni, avx512vl_vnni, neon_dot };

constexpr const char* q8_upgrade_name(Q8Upgrade u) {
  switch (u) {
    case Q8Upgrade::avx_vnni: return "AVX-VNNI (run-time upgrade of the AVX2 build)";
    case Q8Upgrade::avx512vl_vnni: return "AVX-512 VNNI on ymm (run-time upgrade of the AVX2 build)";
    case Q8Upgrade::neon_dot: return "NEON dot product (run-time upgrade of the armv8-a build)";
    default: return "none";
  }
}
// The same as an identifier (benchmark row names, logs): the enumerator's own name.
constexpr const char* q8_upgrade_id(Q8Upgrade u) {
  switch (u) {
    case Q8Upgrade::avx_vnni: return "avx_vnni";
    case Q8Upgrade::avx512vl_vnni: return "avx512vl_vnni";
    case Q8Upgrade::neon_dot: return "neon_dot";
    default: return "none";
  }
}

// Whether this CPU runs upgrade u (and this build has it); the environment plays no part.
inline bool q8_cpu_has(Q8Upgrade u) noexcept {
#if SPARSEBODY_Q8_RUNTIME_X86
  unsigned a = 0, b = 0, c = 0, d = 0;
  if (!__get_cpuid(1, &a, &b, &c, &d) || !(c & (1u << 27))) return false;  // OSXSAVE: xgetbv usable
  unsigned xlo = 0, xhi = 0;
  __asm__ volatile("xgetbv" : "=a"(xlo), "=d"(xhi) : "c"(0));
  if ((xlo & 0x6u) != 0x6u || __get_cpuid_max(0, nullptr) < 7) return false;  // the OS saves ymm
  if (u == Q8Upgrade::avx_vnni) {
    __cpuid_count(7, 1, a, b, c, d);
    return (a >> 4) & 1u;  // CPUID.(7,1):EAX[4] AVX-VNNI
  }
  if (u == Q8Upgrade::avx512vl_vnni) {
    __cpuid_count(7, 0, a, b, c, d);  // EBX[16] AVX512F, EBX[31] AVX512VL, ECX[11] AVX512_VNNI
    return (b >> 16 & 1u) && (b >> 31 & 1u) && (c >> 11 & 1u) && (xlo & 0xe0u) == 0xe0u;  // + opmask/zmm state
  }
#elif SPARSEBODY_Q8_RUNTIME_ARM
  if (u == Q8Upgrade::neon_dot) return (getauxval(AT_HWCAP) >> 20) & 1ul;  // HWCAP_ASIMDDP
#endif
  (void)u;
  return false;
}

// The upgrades in the order gemv() prefers them. AVX-512 VNNI + VL first on CPUs with both (Sapphire
// Rapids, Zen 5): its 32 registers let a batch share each weight load among 4 instances (1.2-1.3x the
// single products at 16 instances on a Sapphire Rapids-class Xeon, where AVX-VNNI's 3 gain ~1.1x); one
// product runs the same on either.
inline constexpr Q8Upgrade kQ8UpgradeOrder[] = {Q8Upgrade::avx512vl_vnni, Q8Upgrade::avx_vnni, Q8Upgrade::neon_dot};

// The upgrade gemv() takes: the first the CPU has, unless SPARSEBODY_Q8_RUNTIME=off (or 0) is in
// the environment (to compare with the build's kernel, or to rule the upgrade out).
inline Q8Upgrade detect_q8_upgrade() noexcept {
  const char* env = std::getenv("SPARSEBODY_Q8_RUNTIME");
  if (env && (std::strcmp(env, "off") == 0 || std::strcmp(env, "0") == 0)) return Q8Upgrade::none;
  for (Q8Upgrade u : kQ8UpgradeOrder)
    if (q8_cpu_has(u)) return u;
  return Q8Upgrade::none;
}


#if SPARSEBODY_Q8_RUNTIME_X86
struct AvxVnniPanel {
  template <int NB> static void run(SPARSEBODY_Q8_PANEL_ARGS) noexcept { q8_panel_vnni256_vex<NB>(w, groups, q, sx, scale, sum, bias, y); }
};
struct AvxVnniBatchPanel {  // VEX code has 16 ymm registers: 3 instances x 4 accumulators + 3 inputs + 1 weight
  static constexpr int M = q8_batch_instances<Q8Kernel::avx_vnni>();
  static void run(SPARSEBODY_Q8_BATCH_ARGS) noexcept { q8_panel_batch_vnni256_vex<M>(w, groups, q, sx, scale, sum, bias, y); }
};
struct Avx512VlVnniPanel {
  template <int NB> static void run(SPARSEBODY_Q8_PANEL_ARGS) noexcept { q8_panel_vnni256_evex<NB>(w, groups, q, sx, scale, sum, bias, y); }
};
struct Avx512VlVnniBatchPanel {  // EVEX code has 32: 4 instances x 4 accumulators (the zmm kernel's grouping)
  static constexpr int M = 4;
  static void run(SPARSEBODY_Q8_BATCH_ARGS) noexcept { q8_panel_batch_vnni256_evex<M>(w, groups, q, sx, scale, sum, bias, y); }
};
#endif

#if SPARSEBODY_Q8_RUNTIME_ARM
struct NeonDotPanel {
  template <int NB> static void run(SPARSEBODY_Q8_PANEL_ARGS) noexcept { q8_panel_sdot<NB>(w, groups, q, sx, scale, sum, bias, y); }
};
struct NeonDotBatchPanel {  // 32 q registers: 4 instances x 4 accumulators
  static constexpr int M = 4;
  static void run(SPARSEBODY_Q8_BATCH_ARGS) noexcept { q8_panel_batch_sdot<M>(w, groups, q, sx, scale, sum, bias, y); }
};
#endif
#undef SPARSEBODY_Q8_PANEL_ARGS
#undef SPARSEBODY_Q8_BATCH_ARGS

// y[0 .. padded(rows)) = W x + bias with Panel's kernel: the input quantized (SIMD loops when kSimd),
// a zero input giving the bias and a non-finite one NaN, then every panel.
template <class Panel, bool kSimd>
inline void gemv_q8_with(const PanelMatrix<float, q8>& W, const float* x, const float* bias, float* y) noexcept {
  alignas(64) std::int8_t q[kQ8MaxCols + 4];
  const float sx = quantize_input_q8<kSimd>(x, W.cols, q);
  const int prows = padded<float>(W.rows);
  if (!(sx > 0.0f)) {  // zero input: y = b; NaN input: NaN
    for (int r = 0; r < prows; ++r) y[r] = sx == 0.0f ? (bias ? bias[r] : 0.0f) : NAN;
    return;
  }
  q8_panels_with<Panel>(W, q, sx, bias, y);
}


// n products with one weight set, equal to n gemv_q8_with<Panel, kSimd> calls bit for bit: each
// instance quantizes its own input; groups of BatchPanel::M instances (M >= 2) share each weight load
// on the full panels; zero / non-finite inputs, the instances left over and the tail rows take
// Panel's single-instance path.
template <class Panel, class BatchPanel, bool kSimd>
inline void gemv_batch_q8_with(const PanelMatrix<float, q8>& W, int n, const float* const* x, const float* bias,
                               float* const* y) noexcept {
  constexpr int M = BatchPanel::M;
  if constexpr (M < 2) {
    for (int i = 0; i < n; ++i) gemv_q8_with<Panel, kSimd>(W, x[i], bias, y[i]);
  } else {
    constexpr int P = kPanelBatches * kLanes<float>;
    alignas(64) std::int8_t q[M][kQ8MaxCols + 4];
    const std::int8_t* qp[M];
    float sx[M];
    float* yp[M];
    const int prows = padded<float>(W.rows);
    const int groups = q8_groups(W.cols);
    const int full = prows / P * P;  // rows in full panels
    int m = 0;
    auto flush = [&](int count) {
      if (count == M) {
        const std::int8_t* w = W.data;
        for (int r0 = 0; r0 < full; r0 += P, w += static_cast<std::size_t>(P) * 4 * groups) {
          float* yr[M];
          for (int k = 0; k < M; ++k) yr[k] = yp[k] + r0;
          BatchPanel::run(w, groups, qp, sx, W.row_scale + r0, W.row_sum + r0, bias ? bias + r0 : nullptr, yr);
        }
        for (int k = 0; k < M; ++k) q8_panels_with<Panel>(W, qp[k], sx[k], bias, yp[k], full);
      } else {
        for (int k = 0; k < count; ++k) q8_panels_with<Panel>(W, qp[k], sx[k], bias, yp[k]);
      }
    };
    for (int i = 0; i < n; ++i) {
      const float s = quantize_input_q8<kSimd>(x[i], W.cols, q[m]);
      if (!(s > 0.0f)) {  // as gemv_q8_with: zero input gives the bias, NaN input NaN
        for (int r = 0; r < prows; ++r) y[i][r] = s == 0.0f ? (bias ? bias[r] : 0.0f) : NAN;
        continue;
      }
      qp[m] = q[m];
      sx[m] = s;
      yp[m] = y[i];
      if (++m == M) {
        flush(M);
        m = 0;
      }
    }
    flush(m);
  }
}

}  // namespace detail

// The upgrade this process runs (decided once, before main: a plain load at step time).
inline const detail::Q8Upgrade kQ8Upgrade = detail::detect_q8_upgrade();

// What gemv() on q8 weights runs in this process: the upgrade's name, else the build's kernel's.
inline const char* q8_kernel_in_use() noexcept {
  return kQ8Upgrade != detail::Q8Upgrade::none ? detail::q8_upgrade_name(kQ8Upgrade) : q8_kernel_name(kQ8Kernel);
}

// y[0 .. padded(rows)) = W x + bias with int8 weights, using kernel Kern (see top; default: the
// build's best). A non-finite x gives NaN outputs (so guarded steps see it), an all-zero x the bias.
template <Q8Kernel Kern = kQ8Kernel>
inline void gemv_q8(const PanelMatrix<float, q8>& W, const float* x, const float* bias, float* y) noexcept {
  detail::gemv_q8_with<detail::BuildPanel<Kern>, Kern != Q8Kernel::portable>(W, x, bias, y);
}

// Batched int8 product with kernel Kern, equal to n gemv_q8<Kern> calls bit for bit: with a
// dot-product kernel (AVX-512 VNNI: 4 instances, AVX-VNNI: 3, NEON dot product: 4) the full panels
// of groups of instances share each weight load (q8_panel_batch); zero / non-finite inputs, the
// instances left over and the tail rows take the single-instance path. Other kernels (AVX2 without
// VNNI: the sign trick needs the input per weight vector; NEON without the dot product; portable)
// run one product per instance.
template <Q8Kernel Kern = kQ8Kernel>
inline void gemv_batch_q8(const PanelMatrix<float, q8>& W, int n, const float* const* x, const float* bias,
                          float* const* y) noexcept {
  detail::gemv_batch_q8_with<detail::BuildPanel<Kern>, detail::BuildBatchPanel<Kern>, Kern != Q8Kernel::portable>(
      W, n, x, bias, y);
}

namespace detail {
// One product and n products with upgrade u's kernels (none: the build's). u must be one this CPU
// runs (q8_cpu_has(u)): on another CPU its instructions are illegal, which is why these are not
// public API. gemv() / gemv_batch() call them with kQ8Upgrade; the tests with each upgrade the CPU has.
// The build's own kernel quantizes with SIMD loops whenever it has an upgrade.
inline void gemv_q8_upgrade(Q8Upgrade u, const PanelMatrix<float, q8>& W, const float* x, const float* bias,
                            float* y) noexcept {
  switch (u) {
#if SPARSEBODY_Q8_RUNTIME_X86
    case Q8Upgrade::avx_vnni: gemv_q8_with<AvxVnniPanel, true>(W, x, bias, y); return;
    case Q8Upgrade::avx512vl_vnni: gemv_q8_with<Avx512VlVnniPanel, true>(W, x, bias, y); return;
#endif
#if SPARSEBODY_Q8_RUNTIME_ARM
    case Q8Upgrade::neon_dot: gemv_q8_with<NeonDotPanel, true>(W, x, bias, y); return;
#endif
    default: gemv_q8<kQ8Kernel>(W, x, bias, y); return;
  }
}
inline void gemv_batch_q8_upgrade(Q8Upgrade u, const PanelMatrix<float, q8>& W, int n, const float* const* x,
                                  const float* bias, float* const* y) noexcept {
  switch (u) {
#if SPARSEBODY_Q8_RUNTIME_X86
    case Q8Upgrade::avx_vnni: gemv_batch_q8_with<AvxVnniPanel, AvxVnniBatchPanel, true>(W, n, x, bias, y); return;
    case Q8Upgrade::avx512vl_vnni:
      gemv_batch_q8_with<Avx512VlVnniPanel, Avx512VlVnniBatchPanel, true>(W, n, x, bias, y);
      return;
#endif
#if SPARSEBODY_Q8_RUNTIME_ARM
    case Q8Upgrade::neon_dot: gemv_batch_q8_with<NeonDotPanel, NeonDotBatchPanel, true>(W, n, x, bias, y); return;
#endif
    default: gemv_batch_q8<kQ8Kernel>(W, n, x, bias, y); return;
  }
}
}  // namespace detail

// The products every network runs: the CPU's upgrade where it has one (kQ8Upgrade), else the
// build's kernel. The branch is taken the same way every call.
inline void gemv(const PanelMatrix<float, q8>& W, const float* x, const float* bias, float* y) noexcept {
#if SPARSEBODY_Q8_RUNTIME_X86 || SPARSEBODY_Q8_RUNTIME_ARM
  if (kQ8Upgrade != detail::Q8Upgrade::none) {
    detail::gemv_q8_upgrade(kQ8Upgrade, W, x, bias, y);
    return;
  }
#endif
  gemv_q8<kQ8Kernel>(W, x, bias, y);
}

inline void gemv_batch(const PanelMatrix<float, q8>& W, int n, const float* const* x, const float* bias,
                       float* const* y) noexcept {
#if SPARSEBODY_Q8_RUNTIME_X86 || SPARSEBODY_Q8_RUNTIME_ARM
  if (kQ8Upgrade != detail::Q8Upgrade::none) {
    detail::gemv_batch_q8_upgrade(kQ8Upgrade, W, n, x, bias, y);
    return;
  }
#endif
  gemv_batch_q8<kQ8Kernel>(W, n, x, bias, y);
}

}  // namespace sparsebody::nn
