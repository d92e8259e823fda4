// float16 weight storage: conversions (portable vs F16C), f16-stored layers against float layers
// holding the same (f16-rounded) weights, and the load-time range check.
#include <cmath>
#include <limits>
#include <random>

#include <doctest/doctest.h>

#include "nn/random_tables.hpp"
#include "sparsebody/networks/lobstr_net.hpp"
#include "sparsebody/nn/half.hpp"
#include "sparsebody/nn/network.hpp"

using namespace sparsebody;
using namespace sparsebody_test;

TEST_CASE("binary16 conversions: exact values, ties to even, subnormals, portable == hardware") {
  CHECK(nn::to_f16_portable(1.0f).bits == 0x3c00);
  CHECK(nn::to_f16_portable(-2.0f).bits == 0xc000);
  CHECK(nn::to_f16_portable(65504.0f).bits == 0x7bff);
  CHECK(nn::to_f16_portable(5.9604645e-8f).bits == 0x0001);  // smallest subnormal
  CHECK(nn::to_f16_portable(1.0f + 1.0f / 2048).bits == 0x3c00);  // tie -> even (down)
  CHECK(nn::to_f16_portable(1.0f + 3.0f / 2048).bits == 0x3c02);  // tie -> even (up)
  CHECK(nn::to_float_portable(nn::f16{0x3555}) == doctest::Approx(0.333251953125).epsilon(1e-12));
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> mant(-1.f, 1.f);
  std::uniform_int_distribution<int> ex(-26, 15);
  for (int i = 0; i < 200000; ++i) {
    const float v = std::ldexp(mant(rng), ex(rng));
    const nn::f16 a = nn::to_f16_portable(v), b = nn::to_f16(v);
    REQUIRE_MESSAGE(a.bits == b.bits, "v = " << v);
    REQUIRE(nn::to_float_portable(a) == nn::to_float(b));
    // rounding error at most half an ulp of binary16 (2^-11 relative, 2^-25 absolute for subnormals)
    REQUIRE(std::abs(nn::to_float(a) - v) <= std::max(std::abs(v) * 0x1p-11f, 0x1p-25f));
  }
}

TEST_CASE("LoBSTr with f16 weights equals the float network holding the same rounded weights, bit for bit") {
  constexpr int H = 45, L = 24;
  using F32 = networks::LoBSTrNet<float, H, L>;
  using F16 = networks::LoBSTrNet<float, H, L, 37, nn::f16>;
  io::TensorTable t = random_lobstr_table(H, L, 4);
  io::TensorTable rounded = t;
  for (auto& kv : rounded.tensors())
    if (kv.first.rfind("gru.weight", 0) == 0 || kv.first == "latent.weight")
      for (double& v : kv.second.values) v = nn::to_float(nn::to_f16(static_cast<float>(v)));
  auto w16 = weights_from_table<F16>(t, "lobstr");
  auto w32 = weights_from_table<F32>(rounded, "lobstr");
  auto w32_exact = weights_from_table<F32>(t, "lobstr");
  CHECK(w16->bytes() < w32->bytes() * 0.6);
  nn::Network<F16> a(w16);
  nn::Network<F32> b(w32), c(w32_exact);
  std::vector<float> x(37);
  double max_rounding_effect = 0;
  for (int s = 0; s < 500; ++s) {
    for (int i = 0; i < 37; ++i) x[i] = std::sin(0.07f * s + 0.5f * i);
    const float* ya = a.step(x.data());
    const float* yb = b.step(x.data());
    const float* yc = c.step(x.data());
    for (int i = 0; i < 52; ++i) {
      REQUIRE(ya[i] == yb[i]);
      max_rounding_effect = std::max(max_rounding_effect, double(std::abs(ya[i] - yc[i])));
    }
  }
  MESSAGE("largest output change from rounding weights to f16: " << max_rounding_effect);
  CHECK(max_rounding_effect > 0);
  CHECK(max_rounding_effect < 1e-2);
}

TEST_CASE("weights outside the float16 range are refused at load") {
  using Net = networks::LoBSTrNet<float, 8, 4, 37, nn::f16>;
  io::TensorTable t("big.json");
  t.tensors() = random_lobstr_table(8, 4, 5).tensors();
  t.tensors()["gru.weight_hh_l0"].values[5] = 70000.0;
  try {
    weights_from_table<Net>(t, "lobstr");
    FAIL("expected LoadError");
  } catch (const LoadError& e) {
    CHECK(std::string(e.what()) ==
          "big.json: tensor 'gru.weight_hh_l0': value 70000.000000 at flat index 5 does not fit float16 weight storage");
  }
}
