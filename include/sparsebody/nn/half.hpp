// IEEE-754 binary16 weight storage ("f16"), an opt-in for layers whose weights stream from memory:
// half the bytes per step. Values are widened to float on load into registers (F16C / AVX-512
// vcvtph2ps, or NEON fcvtl on ARM64, where compiled for; a portable bit conversion otherwise) and all
// arithmetic stays in float, so the only change from float storage is the rounding of each weight to
// 11 significant bits. Worth it where a step is bound by DRAM/L3 bandwidth (e.g. a 1024-wide GRU,
// 12.6 MB in float); for weights that fit in L2 the conversion costs about what the saved bytes gain
// (nn/storage.hpp's fastest_storage() applies that rule).
#pragma once
#include <cmath>
#include <cstdint>
#include <cstring>
#include <type_traits>

#if defined(__AVX512F__) || defined(__F16C__)
#include <immintrin.h>
#endif

namespace sparsebody::nn {

struct f16 {
  std::uint16_t bits = 0;
};

inline constexpr double kF16Max = 65504.0;

// Whether this build widens f16 weights with an instruction (else: the slow portable conversion).
#if defined(__F16C__) || defined(__AVX512F__) || (defined(__aarch64__) && defined(__ARM_NEON))
inline constexpr bool kF16Hardware = true;
#else
inline constexpr bool kF16Hardware = false;
#endif

// Round-to-nearest-even float -> binary16, in portable C++ (values finite and within +/-65504).
inline f16 to_f16_portable(float v) noexcept {
  std::uint32_t x;
  std::memcpy(&x, &v, 4);
  const std::uint32_t sign = (x >> 16) & 0x8000u;
  x &= 0x7fffffffu;
  std::uint16_t h;
  if (x >= 0x477ff000u) {
    h = 0x7c00u;  // overflow -> inf (loaders refuse such weights before this)
  } else if (x < 0x38800000u) {  // subnormal half or zero
    float a;
    std::memcpy(&a, &x, 4);
    h = static_cast<std::uint16_t>(std::nearbyint(a * 16777216.0f));  // a / 2^-24, ties to even
  } else {
    const std::uint32_t mant_odd = (x >> 13) & 1u;
    x += 0xc8000fffu + mant_odd;  // rebias exponent (-112 << 23) and round to nearest even
    h = static_cast<std::uint16_t>(x >> 13);
  }
  return f16{static_cast<std::uint16_t>(h | sign)};
}

inline float to_float_portable(f16 h) noexcept {
  const std::uint32_t sign = static_cast<std::uint32_t>(h.bits & 0x8000u) << 16;
  const std::uint32_t exp = (h.bits >> 10) & 0x1fu, mant = h.bits & 0x3ffu;
  float out;
  if (exp == 0) {
    out = std::ldexp(static_cast<float>(mant), -24);
  } else if (exp == 31) {
    out = mant ? NAN : INFINITY;
  } else {
    const std::uint32_t x = ((exp + 112u) << 23) | (mant << 13);
    std::memcpy(&out, &x, 4);
  }
  return sign ? -out : out;
}

// The same conversions with the F16C instructions when compiled for them.
inline f16 to_f16(float v) noexcept {
#if defined(__F16C__)
  return f16{static_cast<std::uint16_t>(_cvtss_sh(v, _MM_FROUND_TO_NEAREST_INT))};
#else
  return to_f16_portable(v);
#endif
}
inline float to_float(f16 h) noexcept {
#if defined(__F16C__)
  return _cvtsh_ss(h.bits);
#else
  return to_float_portable(h);
#endif
}

// Weight element conversion used when packing: identity for float/double, rounding for f16.
template <typename W>
inline W from_double(double v) noexcept {
  if constexpr (std::is_same_v<W, f16>) return to_f16(static_cast<float>(v));
  else return static_cast<W>(v);
}

}  // namespace sparsebody::nn
