// The arithmetic limit of this build's target, measured: how fast one core multiplies and adds when
// nothing else is in the way (no loads, no dependencies between the chains). Beside a network's
// step it says how close the step is to the FLOP limit, as the plain weight read says how close it
// is to the memory limit; beside a target it says whether the target is reachable at all.
//  - f32: fused multiply-adds on xsimd's widest batch of the build (what nn's float kernels issue);
//  - int8: the instruction sequence of the build's q8 kernel per product (nn/int8.hpp), without its
//    loads: AVX-512 VNNI and AVX-VNNI one vpdpbusd per 64 / 32 products, AVX2 vpsignb + vpmaddubsw +
//    vpmaddwd + vpaddd per 32 (the sign trick that keeps the int16 pair sums exact), NEON with
//    dot-product one sdot per 16, plain NEON smull + sadalp per 8, otherwise scalar int32; where the
//    CPU upgrades gemv at run time (nn/int8.hpp), the upgrade's sequence.
// Each benchmark iteration performs `macs` multiply-adds (rounded up to whole blocks); its time is
// the least a kernel doing that many can take on one core.
#pragma once
#include <cstdint>

#include <benchmark/benchmark.h>
#include <xsimd/xsimd.hpp>

#include "sparsebody/nn/int8.hpp"

#if defined(__AVX2__) || defined(__AVX512F__)
#include <immintrin.h>
#endif
#if defined(__ARM_NEON)
#include <arm_neon.h>
#endif

namespace sparsebody_bench {

inline constexpr int kChains = 12;  // independent accumulators: more than latency x issue width

// f32: kChains FMA chains on the widest batch; returns the multiply-adds done.
inline std::int64_t fma_f32_block(std::int64_t blocks) {
  using B = xsimd::batch<float>;
  B acc[kChains];
  for (int k = 0; k < kChains; ++k) acc[k] = B(1.0f + 1e-3f * k);
  B m(0.9999999f), c(1e-7f);
  benchmark::DoNotOptimize(m);  // opaque: with known constants GCC proves the chains constant and drops them
  benchmark::DoNotOptimize(c);
  for (std::int64_t i = 0; i < blocks; ++i)
    for (int k = 0; k < kChains; ++k) acc[k] = xsimd::fma(acc[k], m, c);
  for (int k = 0; k < kChains; ++k) benchmark::DoNotOptimize(acc[k]);
  return blocks * kChains * std::int64_t(B::size);
}

// The run-time upgrades' sequences (nn/int8.hpp "Run-time upgrade"): one 256-bit vpdpbusd per 32
// products (VEX or EVEX form; the VEX one is also the -mavxvnni build's), one sdot per 16 (also the
// +dotprod build's); compiled for the feature, run only where the CPU has it.
#if SPARSEBODY_Q8_AVX2 && (defined(__GNUC__) || defined(__clang__))
#define SPARSEBODY_BENCH_DPBUSD256(NAME, TARGET, DPBUSD)                                           \
  __attribute__((target(TARGET))) inline std::int64_t NAME(std::int64_t blocks) {                 \
    __m256i acc[kChains];                                                                         \
    for (int k = 0; k < kChains; ++k) acc[k] = _mm256_set1_epi32(k);                              \
    __m256i a = _mm256_set1_epi8(3), b = _mm256_set1_epi8(-5);                                    \
    benchmark::DoNotOptimize(a);                                                                  \
    benchmark::DoNotOptimize(b);                                                                  \
    for (std::int64_t i = 0; i < blocks; ++i)                                                     \
      for (int k = 0; k < kChains; ++k) acc[k] = DPBUSD(acc[k], a, b);                            \
    for (int k = 0; k < kChains; ++k) benchmark::DoNotOptimize(acc[k]);                           \
    return blocks * kChains * 32;                                                                 \
  }
SPARSEBODY_BENCH_DPBUSD256(dot_i8_avx_vnni_rt, "avx2,avxvnni", _mm256_dpbusd_avx_epi32)
SPARSEBODY_BENCH_DPBUSD256(dot_i8_avx512vl_vnni_rt, "avx2,avx512f,avx512vl,avx512vnni", _mm256_dpbusd_epi32)
#undef SPARSEBODY_BENCH_DPBUSD256
#endif
#if SPARSEBODY_Q8_NEON_DOT || SPARSEBODY_Q8_RUNTIME_ARM
#if defined(__clang__)
__attribute__((target("dotprod")))
#else
__attribute__((target("arch=armv8.2-a+dotprod")))
#endif
inline std::int64_t dot_i8_neon_dot_rt(std::int64_t blocks) {
  int32x4_t acc[kChains];
  for (int k = 0; k < kChains; ++k) acc[k] = vdupq_n_s32(k);
  int8x16_t a = vdupq_n_s8(3), b = vdupq_n_s8(-5);
  benchmark::DoNotOptimize(a);
  benchmark::DoNotOptimize(b);
  for (std::int64_t i = 0; i < blocks; ++i)
    for (int k = 0; k < kChains; ++k) acc[k] = vdotq_s32(acc[k], a, b);
  for (int k = 0; k < kChains; ++k) benchmark::DoNotOptimize(acc[k]);
  return blocks * kChains * 16;
}
#endif

// int8 products with int32 sums, the q8 kernel's instructions (the run-time upgrade's where gemv
// takes one); returns the products done.
inline std::int64_t dot_i8_block(std::int64_t blocks) {
  using sparsebody::nn::kQ8Upgrade;
  using sparsebody::nn::detail::Q8Upgrade;
#if SPARSEBODY_Q8_RUNTIME_X86
  if (kQ8Upgrade == Q8Upgrade::avx_vnni) return dot_i8_avx_vnni_rt(blocks);
  if (kQ8Upgrade == Q8Upgrade::avx512vl_vnni) return dot_i8_avx512vl_vnni_rt(blocks);
#endif
#if SPARSEBODY_Q8_RUNTIME_ARM
  if (kQ8Upgrade == Q8Upgrade::neon_dot) return dot_i8_neon_dot_rt(blocks);
#endif
#if SPARSEBODY_Q8_AVX512 && defined(__AVX512VNNI__)
  if constexpr (sparsebody::nn::kQ8Kernel == sparsebody::nn::Q8Kernel::avx512_vnni) {
    __m512i acc[kChains];
    for (int k = 0; k < kChains; ++k) acc[k] = _mm512_set1_epi32(k);
    __m512i a = _mm512_set1_epi8(3), b = _mm512_set1_epi8(-5);
    benchmark::DoNotOptimize(a);
    benchmark::DoNotOptimize(b);
    for (std::int64_t i = 0; i < blocks; ++i)
      for (int k = 0; k < kChains; ++k) acc[k] = _mm512_dpbusd_epi32(acc[k], a, b);
    for (int k = 0; k < kChains; ++k) benchmark::DoNotOptimize(acc[k]);
    return blocks * kChains * 64;
  }
#endif
#if SPARSEBODY_Q8_AVXVNNI && defined(__AVXVNNI__)
  if constexpr (sparsebody::nn::kQ8Kernel == sparsebody::nn::Q8Kernel::avx_vnni) return dot_i8_avx_vnni_rt(blocks);
#endif
#if SPARSEBODY_Q8_AVX2 && defined(__AVX2__)
  if constexpr (sparsebody::nn::kQ8Kernel == sparsebody::nn::Q8Kernel::avx2) {
    __m256i acc[kChains], w[kChains];
    for (int k = 0; k < kChains; ++k) acc[k] = _mm256_set1_epi32(k), w[k] = _mm256_set1_epi8(static_cast<char>(5 + k));
    __m256i q = _mm256_set1_epi8(-3);
    const __m256i ones = _mm256_set1_epi16(1);
    for (std::int64_t i = 0; i < blocks; ++i) {
      benchmark::DoNotOptimize(q);  // a new input word per block (as the kernel's broadcast per column group)
      const __m256i qa = _mm256_abs_epi8(q);  // per input vector, shared by the rows (as in the kernel)
      // a weight vector per chain (as the kernel's rows): with one shared vector the compiler
      // computed sign, vpmaddubsw and vpmaddwd once per block and only the adds per chain,
      // which overstated this limit ~2x (97 G/s on Zen 2 before 2026-12-05)
      for (int k = 0; k < kChains; ++k)
        acc[k] = _mm256_add_epi32(acc[k], _mm256_madd_epi16(_mm256_maddubs_epi16(qa, _mm256_sign_epi8(w[k], q)), ones));
    }
    for (int k = 0; k < kChains; ++k) benchmark::DoNotOptimize(acc[k]);
    return blocks * kChains * 32;
  }
#endif
#if SPARSEBODY_Q8_NEON_DOT && defined(__ARM_FEATURE_DOTPROD)
  if constexpr (sparsebody::nn::kQ8Kernel == sparsebody::nn::Q8Kernel::neon_dot) return dot_i8_neon_dot_rt(blocks);
#endif
#if SPARSEBODY_Q8_NEON && defined(__ARM_NEON)
  if constexpr (sparsebody::nn::kQ8Kernel == sparsebody::nn::Q8Kernel::neon) {
    int32x4_t acc[kChains];
    for (int k = 0; k < kChains; ++k) acc[k] = vdupq_n_s32(k);
    int8x8_t a = vdup_n_s8(3), b[kChains];
    for (int k = 0; k < kChains; ++k) b[k] = vdup_n_s8(static_cast<std::int8_t>(-5 - k));
    for (std::int64_t i = 0; i < blocks; ++i) {
      benchmark::DoNotOptimize(a);  // a new input per block; a weight vector per chain (no shared vmull_s8)
      for (int k = 0; k < kChains; ++k) acc[k] = vpadalq_s16(acc[k], vmull_s8(a, b[k]));
    }
    for (int k = 0; k < kChains; ++k) benchmark::DoNotOptimize(acc[k]);
    return blocks * kChains * 8;
  }
#endif
  std::int32_t acc[kChains];
  for (int k = 0; k < kChains; ++k) acc[k] = k;
  std::int8_t a = 3, b[kChains];
  for (int k = 0; k < kChains; ++k) b[k] = static_cast<std::int8_t>(-5 - k);
  for (std::int64_t i = 0; i < blocks; ++i) {
    benchmark::DoNotOptimize(a);
    for (int k = 0; k < kChains; ++k) acc[k] += std::int32_t(a) * b[k];
  }
  for (int k = 0; k < kChains; ++k) benchmark::DoNotOptimize(acc[k]);
  return blocks * kChains;
}

// One iteration = `macs` multiply-adds at the build's limit (f32 or int8). Counter GMAC/s.
template <bool Int8>
void bench_compute_limit(benchmark::State& st, std::int64_t macs) {
  const std::int64_t per_block = Int8 ? dot_i8_block(1) : fma_f32_block(1);
  const std::int64_t blocks = (macs + per_block - 1) / per_block;
  std::int64_t done = 0;
  for (auto _ : st) done += Int8 ? dot_i8_block(blocks) : fma_f32_block(blocks);
  st.counters["GMAC/s"] = benchmark::Counter(double(done) * 1e-9, benchmark::Counter::kIsRate);
  st.counters["macs"] = double(blocks * per_block);
}

}  // namespace sparsebody_bench
