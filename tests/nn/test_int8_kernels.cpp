// Every int8 kernel compiled into this build (nn/int8.hpp: AVX-512 VNNI, AVX-VNNI, AVX2, NEON dot
// product, NEON) gives the portable kernel's result bit for bit: random weights and inputs at every
// panel-tail size, and the extremes (rows and inputs at +-127 everywhere: the largest int16 pair
// sums, where a careless vpmaddubsw would saturate). Built for each target ISA the CI covers
// (native, x86-64-v3, x86-64-v3 + AVX-VNNI, x86-64, ARM64 with and without dot product); each build
// checks the kernels it has and says which.
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <doctest/doctest.h>
#include <limits>

#include "sparsebody/core/aligned_buffer.hpp"
#include "sparsebody/nn/int8.hpp"
#include "nn/packed_q8.hpp"
#include "sparsebody/nn/storage.hpp"

using namespace sparsebody;
using nn::Q8Kernel;

namespace {

constexpr Q8Kernel kAll[] = {Q8Kernel::avx512_vnni, Q8Kernel::avx_vnni, Q8Kernel::avx2, Q8Kernel::neon_dot, Q8Kernel::neon};

using Packed = sparsebody_test::PackedQ8;  // a packed q8 matrix owning its storage (nn/packed_q8.hpp)

// kind 0: N(0,1); 1: +-1 only (every Q or q at +-127); 2: mixed, half the entries at +-1.
float draw(std::mt19937& rng, int kind) {
  std::normal_distribution<float> d(0.f, 1.f);
  const float s = (rng() & 1) ? 1.f : -1.f;
  if (kind == 1) return s;
  if (kind == 2) return (rng() & 1) ? s : 0.5f * d(rng);
  return d(rng);
}

template <Q8Kernel K>
void gemv_if(const nn::PanelMatrix<float, nn::q8>& m, const float* x, const float* b, float* y) {
  if constexpr (nn::q8_kernel_available(K)) nn::gemv_q8<K>(m, x, b, y);
}
void gemv_kernel(Q8Kernel k, const nn::PanelMatrix<float, nn::q8>& m, const float* x, const float* b, float* y) {
  switch (k) {
    case Q8Kernel::avx512_vnni: gemv_if<Q8Kernel::avx512_vnni>(m, x, b, y); break;
    case Q8Kernel::avx_vnni: gemv_if<Q8Kernel::avx_vnni>(m, x, b, y); break;
    case Q8Kernel::avx2: gemv_if<Q8Kernel::avx2>(m, x, b, y); break;
    case Q8Kernel::neon_dot: gemv_if<Q8Kernel::neon_dot>(m, x, b, y); break;
    case Q8Kernel::neon: gemv_if<Q8Kernel::neon>(m, x, b, y); break;
    default: gemv_if<Q8Kernel::portable>(m, x, b, y); break;
  }
}
constexpr bool available(Q8Kernel k) {
  switch (k) {
    case Q8Kernel::avx512_vnni: return nn::q8_kernel_available(Q8Kernel::avx512_vnni);
    case Q8Kernel::avx_vnni: return nn::q8_kernel_available(Q8Kernel::avx_vnni);
    case Q8Kernel::avx2: return nn::q8_kernel_available(Q8Kernel::avx2);
    case Q8Kernel::neon_dot: return nn::q8_kernel_available(Q8Kernel::neon_dot);
    case Q8Kernel::neon: return nn::q8_kernel_available(Q8Kernel::neon);
    default: return true;
  }
}

bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof(float)) == 0; }

}  // namespace

TEST_CASE("int8 kernels of this build equal the portable kernel bit for bit, extremes included") {
  std::string tested;
  for (Q8Kernel k : kAll)
    if (available(k)) tested += std::string(tested.empty() ? "" : ", ") + nn::q8_kernel_name(k);
  MESSAGE("lanes " << nn::kLanes<float> << "; gemv uses " << std::string(nn::q8_kernel_name(nn::kQ8Kernel))
                   << "; kernels compared with portable: " << (tested.empty() ? "none (portable only)" : tested));
  std::mt19937 rng(7);
  constexpr int L = nn::kLanes<float>;
  // Rows: every tail batch count 1..7 of a panel, whole panels, several panels plus a tail.
  const int row_counts[] = {1, L - 1 > 0 ? L - 1 : 1, 2 * L + 3, 5 * L, 7 * L + 1, 8 * L, 8 * L + 5, 19 * L + 2};
  const int col_counts[] = {1, 3, 4, 5, 8, 37, 64, 129, 868};
  long compared = 0;
  for (int rows : row_counts)
    for (int cols : col_counts)
      for (int kind = 0; kind < 3; ++kind) {
        std::vector<float> w(static_cast<std::size_t>(rows) * cols);
        for (float& v : w) v = draw(rng, kind);
        Packed p(w, rows, cols);
        AlignedBuffer<float> bias(nn::padded<float>(rows)), y0(nn::padded<float>(rows)), y1(nn::padded<float>(rows));
        for (int r = 0; r < rows; ++r) bias[r] = draw(rng, 0);
        std::vector<float> x(cols);
        for (int rep = 0; rep < 3; ++rep) {
          for (float& v : x) v = draw(rng, rep == 0 ? 1 : kind) * (rep == 2 ? 1e-3f : 1.f);
          gemv_kernel(Q8Kernel::portable, p.m, x.data(), rep == 1 ? nullptr : bias.data(), y0.data());
          for (Q8Kernel k : kAll) {
            if (!available(k)) continue;
            for (int r = 0; r < nn::padded<float>(rows); ++r) y1[r] = -12345.f;
            gemv_kernel(k, p.m, x.data(), rep == 1 ? nullptr : bias.data(), y1.data());
            for (int r = 0; r < nn::padded<float>(rows); ++r)
              REQUIRE_MESSAGE(same_bits(y0[r], y1[r]), nn::q8_kernel_name(k) << " rows " << rows << " cols " << cols
                                                                            << " kind " << kind << " rep " << rep << " row " << r
                                                                            << ": " << y1[r] << " vs portable " << y0[r]);
            ++compared;
          }
        }
      }
  MESSAGE(compared << " products compared");
}

TEST_CASE("int8 run-time upgrades this CPU has equal the portable kernel bit for bit; gemv() takes the first") {
  // nn/int8.hpp "Run-time upgrade": an AVX2 build on a VNNI CPU, an armv8-a build on a dot-product
  // CPU. Each upgrade the CPU runs is compared on the first test's grid and on the +-127 extreme;
  // the ones it lacks are named as skipped (on this build's CPU the list says which ran).
  using nn::detail::Q8Upgrade;
  std::string ran, skipped;
  std::mt19937 rng(11);
  constexpr int L = nn::kLanes<float>;
  const int row_counts[] = {1, 2 * L + 3, 7 * L + 1, 8 * L, 19 * L + 2};
  const int col_counts[] = {1, 5, 37, 129, 868};
  long compared = 0;
  for (Q8Upgrade u : {Q8Upgrade::avx_vnni, Q8Upgrade::avx512vl_vnni, Q8Upgrade::neon_dot}) {
    if (!nn::detail::q8_cpu_has(u)) {
      skipped += std::string(skipped.empty() ? "" : "; ") + nn::detail::q8_upgrade_name(u);
      continue;
    }
    ran += std::string(ran.empty() ? "" : "; ") + nn::detail::q8_upgrade_name(u);
    for (int rows : row_counts)
      for (int cols : col_counts)
        for (int kind = 0; kind < 3; ++kind) {
          std::vector<float> w(static_cast<std::size_t>(rows) * cols);
          for (float& v : w) v = draw(rng, kind);
          if (kind == 1 && rows == 8 * L)  // the extreme: every Q and q at +-127, sums of 127 * 127 * cols
            for (int r = 0; r < rows; ++r)
              for (int c = 0; c < cols; ++c) w[static_cast<std::size_t>(r) * cols + c] = r % 2 ? -1.f : 1.f;
          Packed p(w, rows, cols);
          AlignedBuffer<float> bias(nn::padded<float>(rows)), y0(nn::padded<float>(rows)), y1(nn::padded<float>(rows));
          for (int r = 0; r < rows; ++r) bias[r] = draw(rng, 0);
          std::vector<float> x(cols);
          for (int rep = 0; rep < 3; ++rep) {
            for (float& v : x) v = rep == 0 ? 1.f : draw(rng, kind) * (rep == 2 ? 1e-3f : 1.f);
            gemv_kernel(Q8Kernel::portable, p.m, x.data(), rep == 1 ? nullptr : bias.data(), y0.data());
            for (int r = 0; r < nn::padded<float>(rows); ++r) y1[r] = -12345.f;
            nn::detail::gemv_q8_upgrade(u, p.m, x.data(), rep == 1 ? nullptr : bias.data(), y1.data());
            for (int r = 0; r < nn::padded<float>(rows); ++r)
              REQUIRE_MESSAGE(same_bits(y0[r], y1[r]), nn::detail::q8_upgrade_name(u) << " rows " << rows << " cols " << cols
                                                                                      << " kind " << kind << " rep " << rep
                                                                                      << " row " << r << ": " << y1[r]
                                                                                      << " vs portable " << y0[r]);
            ++compared;
          }
        }
  }
  MESSAGE("upgrades compared with portable: " << (ran.empty() ? "none" : ran) << " (" << compared
                                              << " products); not on this CPU or build: " << (skipped.empty() ? "none" : skipped));
  // gemv() runs the first upgrade the CPU has, unless SPARSEBODY_Q8_RUNTIME=off (or 0).
  const char* env = std::getenv("SPARSEBODY_Q8_RUNTIME");
  const bool off = env && (std::string(env) == "off" || std::string(env) == "0");
  Q8Upgrade expect = Q8Upgrade::none;
  for (Q8Upgrade u : nn::detail::kQ8UpgradeOrder)
    if (!off && expect == Q8Upgrade::none && nn::detail::q8_cpu_has(u)) expect = u;
  CHECK(nn::kQ8Upgrade == expect);
  MESSAGE("gemv runs: " << std::string(nn::q8_kernel_in_use()) << std::string(off ? " (SPARSEBODY_Q8_RUNTIME=off)" : ""));
#if !SPARSEBODY_Q8_RUNTIME_X86 && !SPARSEBODY_Q8_RUNTIME_ARM
  CHECK(nn::kQ8Upgrade == Q8Upgrade::none);  // builds with a dot product of their own, or no SIMD kernel
  CHECK(ran.empty());
#endif
  // And gemv() itself (whichever kernel it runs) equals portable.
  std::vector<float> w(static_cast<std::size_t>(150) * 868), x(868);
  for (float& v : w) v = draw(rng, 0);
  for (float& v : x) v = draw(rng, 0);
  Packed p(w, 150, 868);
  AlignedBuffer<float> y0(nn::padded<float>(150)), y1(nn::padded<float>(150));
  gemv_kernel(Q8Kernel::portable, p.m, x.data(), nullptr, y0.data());
  nn::gemv(p.m, x.data(), nullptr, y1.data());
  for (int r = 0; r < 150; ++r) REQUIRE(same_bits(y0[r], y1[r]));
}

TEST_CASE("int8 kernels: the all-+-127 extreme gives the exact integer sum") {
  // Every weight and input at +1 -> Q = q = 127: S_r = 127 * 127 * cols (an int16 pair sum of
  // 32258: exact only if nothing saturates); signs alternating per row flip it.
  constexpr int rows = 3 * nn::kLanes<float>, cols = 868;
  std::vector<float> w(static_cast<std::size_t>(rows) * cols);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) w[static_cast<std::size_t>(r) * cols + c] = (r % 2 ? -1.f : 1.f);
  Packed p(w, rows, cols);
  std::vector<float> x(cols, 1.f);
  AlignedBuffer<float> y(nn::padded<float>(rows));
  for (Q8Kernel k : {Q8Kernel::portable, Q8Kernel::avx512_vnni, Q8Kernel::avx_vnni, Q8Kernel::avx2, Q8Kernel::neon_dot, Q8Kernel::neon}) {
    if (!available(k)) continue;
    gemv_kernel(k, p.m, x.data(), nullptr, y.data());
    const float expect = std::fma(127.f * 127.f * cols, (1.f / 127.f) * (1.f / 127.f), 0.f);
    for (int r = 0; r < rows; ++r) REQUIRE_MESSAGE(same_bits(y[r], r % 2 ? -expect : expect), nn::q8_kernel_name(k) << " row " << r);
  }
}

TEST_CASE("int8 input quantization: the SIMD loop equals the scalar scheme, ties to even included") {
  std::mt19937 rng(3);
  std::vector<float> x(1031);
  alignas(64) std::int8_t qa[nn::kQ8MaxCols + 4], qb[nn::kQ8MaxCols + 4];
  for (int rep = 0; rep < 200; ++rep) {
    const int cols = 1 + static_cast<int>(rng() % x.size());
    for (int j = 0; j < cols; ++j) x[j] = draw(rng, rep % 3) * std::ldexp(1.f, static_cast<int>(rng() % 40) - 20);
    if (rep % 5 == 0)  // exact halves after scaling by 127 / amax = 1: round-half-to-even matters
      for (int j = 0; j < cols; ++j) x[j] = (j == 0 ? 127.f : 0.5f + static_cast<float>(j % 7));
    const float sa = nn::detail::quantize_input_q8<true>(x.data(), cols, qa);
    const float sb = nn::detail::quantize_input_q8<false>(x.data(), cols, qb);
    REQUIRE(same_bits(sa, sb));
    REQUIRE(std::memcmp(qa, qb, 4 * nn::q8_groups(cols)) == 0);
  }
}

TEST_CASE("pack_q8 stores only -127..127 (the AVX2 kernel's sign trick needs no -128)") {
  std::mt19937 rng(5);
  constexpr int rows = 37, cols = 53;
  std::vector<float> w(rows * cols);
  for (float& v : w) v = draw(rng, 2) * 3.f;
  Packed p(w, rows, cols);
  int lo = 0, hi = 0;
  for (std::size_t i = 0; i < static_cast<std::size_t>(nn::padded<float>(rows)) * 4 * nn::q8_groups(cols); ++i)
    lo = std::min<int>(lo, p.q[i]), hi = std::max<int>(hi, p.q[i]);
  CHECK(lo == -127);
  CHECK(hi == 127);
}

TEST_CASE("storage auto: q8 exactly where the build has a SIMD int8 kernel, else f16 only beyond L2") {
  constexpr nn::StorageChoice c = nn::fastest_storage();  // decided at compile time
  MESSAGE("storage auto -> " << std::string(nn::storage_name(c.storage)) << " (" << std::string(c.reason) << ")");
  CHECK((c.storage == nn::Storage::q8) == (nn::kQ8Kernel != Q8Kernel::portable));
  if (nn::kQ8Kernel == Q8Kernel::portable) {
    CHECK(c.storage == nn::Storage::f32);
    CHECK(nn::fastest_storage(nn::kF16MinFloatBytes).storage == nn::Storage::f32);
    CHECK(nn::fastest_storage(nn::kF16MinFloatBytes + 1).storage == (nn::kF16Hardware ? nn::Storage::f16 : nn::Storage::f32));
  }
#if defined(__aarch64__)
  CHECK(c.storage == nn::Storage::q8);  // every ARM64 build has NEON
#endif
}

TEST_CASE("int8 batched product: zero and NaN inputs inside a group of instances, full panels and tails, equal to singles") {
  // gemv_batch_q8 shares weight loads across groups of instances (VNNI builds) and sends zero /
  // non-finite inputs, left-over instances and tail rows to the single-instance path.
  using W = nn::PanelMatrix<float, nn::q8>;
  std::mt19937 rng(5);
  std::normal_distribution<float> d(0.f, 1.f);
  for (int rows : {128, 150, 300}) {
    for (int cols : {37, 256}) {
      std::vector<float> dense(static_cast<std::size_t>(rows) * cols), bias(static_cast<std::size_t>(nn::padded<float>(rows)));
      for (float& v : dense) v = d(rng);
      for (float& v : bias) v = d(rng);
      const Packed packed(dense, rows, cols);
      const W& m = packed.m;
      for (int n : {1, 4, 7, 9}) {
        std::vector<std::vector<float>> x(n, std::vector<float>(cols));
        for (int i = 0; i < n; ++i)
          for (float& v : x[i]) v = d(rng) * (i + 1);
        if (n >= 4) std::fill(x[1].begin(), x[1].end(), 0.f);          // zero input: the bias
        if (n >= 7) x[5][3] = std::numeric_limits<float>::quiet_NaN();  // NaN input: NaN rows
        std::vector<std::vector<float>> yb(n, std::vector<float>(bias.size())), ys = yb;
        std::vector<const float*> xp(n);
        std::vector<float*> yp(n);
        for (int i = 0; i < n; ++i) xp[i] = x[i].data(), yp[i] = yb[i].data();
        nn::gemv_batch(m, n, xp.data(), bias.data(), yp.data());
        for (int i = 0; i < n; ++i) {
          nn::gemv(m, x[i].data(), bias.data(), ys[i].data());
          CAPTURE(rows);
          CAPTURE(cols);
          CAPTURE(n);
          CAPTURE(i);
          REQUIRE(std::memcmp(ys[i].data(), yb[i].data(), sizeof(float) * bias.size()) == 0);
        }
      }
    }
  }
}

TEST_CASE("int8 batched run-time upgrades this CPU has equal portable single products bit for bit") {
  // detail::gemv_batch_q8_upgrade: groups of 2 (AVX-VNNI) or 4 (AVX-512 VNNI on ymm, NEON dot product)
  // instances share each weight load on the full panels; the rest goes one by one. Instance counts
  // around the group sizes, zero and NaN inputs inside a group, panels with and without tails.
  using nn::detail::Q8Upgrade;
  using W = nn::PanelMatrix<float, nn::q8>;
  constexpr int L = nn::kLanes<float>;
  std::mt19937 rng(17);
  std::normal_distribution<float> d(0.f, 1.f);
  std::string ran;
  long compared = 0;
  for (Q8Upgrade u : {Q8Upgrade::avx_vnni, Q8Upgrade::avx512vl_vnni, Q8Upgrade::neon_dot, Q8Upgrade::none}) {
    if (u != Q8Upgrade::none && !nn::detail::q8_cpu_has(u)) continue;
    ran += std::string(ran.empty() ? "" : "; ") +
           (u == Q8Upgrade::none ? std::string("the build's kernel, ") + nn::q8_kernel_name(nn::kQ8Kernel)
                                 : std::string(nn::detail::q8_upgrade_name(u)));
    for (int rows : {3, 8 * L, 8 * L + 5, 24 * L + 2 * L})
      for (int cols : {5, 37, 868}) {
        std::vector<float> dense(static_cast<std::size_t>(rows) * cols), bias(static_cast<std::size_t>(nn::padded<float>(rows)));
        for (float& v : dense) v = draw(rng, 2);
        for (float& v : bias) v = d(rng);
        const Packed packed(dense, rows, cols);
        const W& m = packed.m;
        for (int n : {1, 2, 3, 4, 5, 8, 11, 16}) {
          std::vector<std::vector<float>> x(n, std::vector<float>(cols));
          for (int i = 0; i < n; ++i)
            for (float& v : x[i]) v = d(rng) * static_cast<float>(i + 1);
          if (n >= 3) std::fill(x[1].begin(), x[1].end(), 0.f);          // zero input: the bias
          if (n >= 8) x[6][cols / 2] = std::numeric_limits<float>::quiet_NaN();  // NaN input: NaN rows
          std::vector<std::vector<float>> yb(n, std::vector<float>(bias.size(), -1.f)), ys = yb;
          std::vector<const float*> xp(n);
          std::vector<float*> yp(n);
          for (int i = 0; i < n; ++i) xp[i] = x[i].data(), yp[i] = yb[i].data();
          nn::detail::gemv_batch_q8_upgrade(u, m, n, xp.data(), n % 2 ? bias.data() : nullptr, yp.data());
          for (int i = 0; i < n; ++i) {
            gemv_kernel(Q8Kernel::portable, m, x[i].data(), n % 2 ? bias.data() : nullptr, ys[i].data());
            CAPTURE(rows);
            CAPTURE(cols);
            CAPTURE(n);
            CAPTURE(i);
            for (int r = 0; r < nn::padded<float>(rows); ++r)
              REQUIRE_MESSAGE(same_bits(ys[i][r], yb[i][r]), nn::detail::q8_upgrade_name(u) << " row " << r << ": " << yb[i][r]
                                                                                  << " vs portable " << ys[i][r]);
            ++compared;
          }
        }
      }
  }
  MESSAGE("batched, compared with portable singles: " << ran << " (" << compared << " instance products)");
}
