// int8 weight storage (nn/int8.hpp): the packed product equals the documented quantization scheme
// computed independently here (any size, row re-placement), non-finite and zero inputs, and a
// whole network's drift from float over a long stateful sequence. Built twice: AVX-512 VNNI kernel
// (when the machine has it) and the portable path (-mno-avx).
#include <cmath>
#include <random>
#include <vector>

#include <doctest/doctest.h>

#include "nn/random_tables.hpp"
#include "sparsebody/networks/lobstr_net.hpp"
#include "sparsebody/nn/dense.hpp"
#include "sparsebody/nn/int8.hpp"
#include "sparsebody/nn/network.hpp"

using namespace sparsebody;
using namespace sparsebody_test;

namespace {

inline constexpr char kD[] = "d";

// y = b + s_r s_x sum_j Q_rj q_j with the scheme's definitions, from the raw weights.
std::vector<double> reference(const io::Tensor& w, const io::Tensor& b, const std::vector<float>& x) {
  const int rows = static_cast<int>(w.shape[0]), cols = static_cast<int>(w.shape[1]);
  float amax = 0;
  for (float v : x) amax = std::max(amax, std::abs(v));
  const float inv = 127.0f / amax, sx = amax / 127.0f;
  std::vector<int> q(cols);
  for (int j = 0; j < cols; ++j) q[j] = static_cast<int>(std::nearbyint(x[j] * inv));
  std::vector<double> y(rows);
  for (int r = 0; r < rows; ++r) {
    double m = 0;
    for (int c = 0; c < cols; ++c) m = std::max(m, std::abs(w.values[r * cols + c]));
    const float sr = m > 0 ? static_cast<float>(m / 127.0) : 1.0f;
    long long acc = 0;
    for (int c = 0; c < cols; ++c) acc += static_cast<long long>(std::nearbyint(w.values[r * cols + c] / sr)) * q[c];
    y[r] = b.values[r] + static_cast<double>(sr) * sx * static_cast<double>(acc);
  }
  return y;
}

template <int In, int Out>
void check_dense(unsigned seed) {
  using Net = nn::Named<kD, nn::Dense<float, In, Out, nn::Identity, true, nn::q8>>;
  using Ref = nn::Named<kD, nn::Dense<float, In, Out, nn::Identity, true, float>>;
  std::mt19937 rng(seed);
  io::TensorTable t("random");
  add_linear(t, "d.", In, Out, rng);
  const io::Tensor w = t.tensors().at("d.weight"), b = t.tensors().at("d.bias");
  auto wq = weights_from_table<Net>(t, "test");
  auto wf = weights_from_table<Ref>(t, "test");
  nn::Network<Net> net(wq);
  nn::Network<Ref> ref(wf);
  std::normal_distribution<float> d(0.f, 1.f);
  std::vector<float> x(In);
  double worst_scheme = 0, worst_float = 0, scale = 0;
  for (int rep = 0; rep < 20; ++rep) {
    for (float& v : x) v = d(rng) * (rep % 3 == 0 ? 1e-3f : 1.0f);
    const float* y = net.step(x.data());
    const float* yf = ref.step(x.data());
    const std::vector<double> yr = reference(w, b, x);
    double ymax = 0;
    for (int r = 0; r < Out; ++r) ymax = std::max(ymax, std::abs(yr[r]));
    for (int r = 0; r < Out; ++r) {
      worst_scheme = std::max(worst_scheme, std::abs(y[r] - yr[r]) / (ymax + 1e-30));
      worst_float = std::max(worst_float, std::abs(double(y[r]) - yf[r]) / (ymax + 1e-30));
    }
    scale = std::max(scale, ymax);
  }
  INFO("In " << In << " Out " << Out);
  CHECK(worst_scheme < 2e-6);  // float rounding of the final scale-and-add only
  CHECK(worst_float < 0.03);   // quantization error against the float layer, relative to max |y|
}

}  // namespace

TEST_CASE("q8 Dense equals the quantization scheme at sizes that are not SIMD multiples") {
  check_dense<1, 1>(1);
  check_dense<3, 5>(2);
  check_dense<37, 45>(3);
  check_dense<128, 257>(4);
  check_dense<475, 400>(5);
  check_dense<600, 131>(6);
  check_dense<5, 300>(7);
}

TEST_CASE("q8 product: zero input gives the bias, non-finite input gives NaN (for guarded steps)") {
  using Net = nn::Named<kD, nn::Dense<float, 20, 19, nn::Identity, true, nn::q8>>;
  std::mt19937 rng(9);
  io::TensorTable t("random");
  add_linear(t, "d.", 20, 19, rng);
  const io::Tensor b = t.tensors().at("d.bias");
  nn::Network<Net> net(weights_from_table<Net>(t, "test"));
  std::vector<float> x(20, 0.f);
  const float* y = net.step(x.data());
  for (int r = 0; r < 19; ++r) CHECK(y[r] == static_cast<float>(b.values[r]));
  x[17] = NAN;
  y = net.step(x.data());
  for (int r = 0; r < 19; ++r) CHECK(std::isnan(y[r]));
  x[17] = INFINITY;
  y = net.step(x.data());
  for (int r = 0; r < 19; ++r) CHECK(std::isnan(y[r]));
}

TEST_CASE("LoBSTr with q8 weights stays close to float over 1000 stateful steps, with under half the bytes") {
  constexpr int H = 45, L = 24;
  using F32 = networks::LoBSTrNet<float, H, L>;
  using Q8 = networks::LoBSTrNet<float, H, L, 37, nn::q8>;
  io::TensorTable t = random_lobstr_table(H, L, 4);
  auto wq = weights_from_table<Q8>(t, "lobstr");
  auto wf = weights_from_table<F32>(t, "lobstr");
  CHECK(wq->bytes() < wf->bytes() * 0.45);  // biases, scales and row sums stay 4 bytes
  nn::Network<Q8> a(wq);
  nn::Network<F32> b(wf);
  std::vector<float> x(37);
  double worst = 0, mean = 0;
  long n = 0;
  for (int s = 0; s < 1000; ++s) {
    for (int i = 0; i < 37; ++i) x[i] = std::sin(0.07f * s + 0.5f * i);
    const float* ya = a.step(x.data());
    const float* yb = b.step(x.data());
    for (int i = 0; i < 52; ++i) {
      const double e = std::abs(double(ya[i]) - yb[i]);
      worst = std::max(worst, e);
      mean += e, ++n;
    }
  }
  MESSAGE("q8 vs float LoBSTr (H=45), 1000 steps: worst " << worst << ", mean " << mean / n);
  CHECK(worst > 0);
  // A random GRU (weights N(0, 0.3)) amplifies perturbations more than trained ones do: these bounds
  // catch a broken kernel (errors of order 1), not the task accuracy, which the N3P evaluation gives.
  CHECK(worst < 0.25);
  CHECK(mean / n < 0.03);
}

TEST_CASE("q8 refuses non-finite weights and over-long rows at load, naming the tensor") {
  using Net = networks::LoBSTrNet<float, 8, 4, 37, nn::q8>;
  io::TensorTable t("bad.json");
  t.tensors() = random_lobstr_table(8, 4, 5).tensors();
  t.tensors()["gru.weight_hh_l0"].values[5] = NAN;
  try {
    weights_from_table<Net>(t, "lobstr");
    FAIL("expected LoadError");
  } catch (const LoadError& e) {
    CHECK(std::string(e.what()) == "bad.json: tensor 'gru.weight_hh_l0': non-finite value at flat index 5");
  }
}
