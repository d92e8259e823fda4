// "storage auto": which weight storage (float, f16, q8) runs a float network fastest in this build,
// decided at compile time from the target ISA (no -march=native assumption). The q8 kernel itself
// may be upgraded at run time to a dot product the CPU has (nn/int8.hpp, q8_kernel_in_use()); that
// only makes q8 faster, so the choice stands.
//
// Rule (README "Network benchmarks", bench/bench_networks.cpp, measured per build target):
//  1. q8 where the build has a SIMD int8 kernel (nn::kQ8Kernel: AVX-512 VNNI, AVX-VNNI, AVX2,
//     NEON dot product, NEON): it streams a quarter of the float bytes and its integer sums keep up
//     with the stream. Measured faster than float for every paper network on AVX-512 VNNI and AVX2
//     builds; the NEON kernels are checked for exactness under qemu only (no ARM timings here).
//  2. else f16 where the build widens f16 in hardware (F16C, NEON) and the float weights exceed
//     kF16MinFloatBytes: below that they sit in L2, where the widening costs about what the saved
//     bytes gain, so f16 is not reliably faster there and auto keeps float.
//  3. else float (a generic x86-64 build: the portable int8 and f16 paths are exact but slow).
// q8 changes outputs by ~1e-3 relative (int8.hpp); choose a storage explicitly where that matters.
#pragma once
#include <cstddef>

#include "sparsebody/nn/half.hpp"
#include "sparsebody/nn/int8.hpp"

namespace sparsebody::nn {

enum class Storage { f32, f16, q8 };

constexpr const char* storage_name(Storage s) {
  return s == Storage::q8 ? "q8" : s == Storage::f16 ? "f16" : "float";
}

// Float weight bytes above which f16 pays without an int8 kernel (about a core's L2).
inline constexpr std::size_t kF16MinFloatBytes = std::size_t(2) << 20;

struct StorageChoice {
  Storage storage;
  const char* reason;  // one line, for logs and the demo
};

// float_weight_bytes: the network's weights in float (NetworkWeights<float net>::bytes()); 0 when
// unknown, which never picks f16.
constexpr StorageChoice fastest_storage(std::size_t float_weight_bytes = 0) noexcept {
  switch (kQ8Kernel) {
    case Q8Kernel::avx512_vnni: return {Storage::q8, "AVX-512 VNNI int8 kernel: 2.2-5.3x float in bench_networks, Zen 5"};
    case Q8Kernel::avx_vnni: return {Storage::q8, "AVX-VNNI int8 kernel: 1.9-5.0x float in bench_networks, Zen 5"};
    case Q8Kernel::avx2: return {Storage::q8, "AVX2 int8 kernel (upgraded to VNNI at run time where the CPU has it): 1.6-3.6x float in bench_networks, Zen 5; 1.9-4.3x with the upgrade, Intel Xeon"};
    case Q8Kernel::neon_dot: return {Storage::q8, "NEON dot-product int8 kernel: 16 multiply-adds per instruction, a quarter of the bytes"};
    case Q8Kernel::neon: return {Storage::q8, "NEON int8 kernel (upgraded to the dot product at run time where the CPU has it): a quarter of the bytes; not timed on hardware"};
    default: break;
  }
  if (kF16Hardware && float_weight_bytes > kF16MinFloatBytes)
    return {Storage::f16, "no SIMD int8 kernel in this build; f16 widened in hardware halves weights beyond L2"};
  return {Storage::f32, kF16Hardware ? "no SIMD int8 kernel in this build; weights fit in L2, where f16 does not pay"
                                     : "no SIMD int8 kernel or f16 conversion in this build (generic target)"};
}

}  // namespace sparsebody::nn
