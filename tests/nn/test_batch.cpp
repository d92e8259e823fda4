// NetworkBatch (nn/batch.hpp): N instances stepped together equal N separate Network instances bit
// for bit (GRU stacks and MLPs; float, double, f16 and q8 storage; instance counts that fill the
// instance tiles and ones that leave a remainder), keep their own state, and never allocate per step.
#include "support/alloc_counter.hpp"

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include <doctest/doctest.h>

#include "nn/random_tables.hpp"
#include "sparsebody/nn/batch.hpp"
#include "sparsebody/nn/gru.hpp"
#include "sparsebody/nn/mlp.hpp"

using namespace sparsebody;
using namespace sparsebody_test;

namespace {

inline constexpr char kGru[] = "gru";
inline constexpr char kMlp[] = "layers";
template <typename T, typename W>
using GruStack = nn::Named<kGru, nn::GRU<T, 23, 45, 3, W>>;
template <typename T, typename W>
using Mlp = nn::Named<kMlp, nn::MLPStored<T, W, nn::Tanh, nn::Identity, 37, 70, 33, 9>>;

io::TensorTable gru_table() {
  std::mt19937 rng(11);
  io::TensorTable t("random");
  add_gru(t, "gru.", 23, 45, 3, rng);
  return t;
}
io::TensorTable mlp_table() {
  std::mt19937 rng(12);
  io::TensorTable t("random");
  add_linear(t, "layers.0.", 37, 70, rng);
  add_linear(t, "layers.1.", 70, 33, rng);
  add_linear(t, "layers.2.", 33, 9, rng);
  return t;
}

template <class Net>
void check_equal_to_singles(const io::TensorTable& table, int n, int steps = 40) {
  using T = typename Net::scalar;
  auto w = weights_from_table<Net>(table, "test");
  nn::NetworkBatch<Net> batch(w, n);
  std::vector<nn::Network<Net>> singles;
  for (int i = 0; i < n; ++i) singles.emplace_back(w);
  std::vector<std::vector<T>> x(n, std::vector<T>(Net::in_size));
  std::vector<const T*> xp(n);
  for (int i = 0; i < n; ++i) xp[i] = x[i].data();
  for (int t = 0; t < steps; ++t) {
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < Net::in_size; ++j) x[i][j] = static_cast<T>(std::sin(0.1 * t + 0.37 * j + 1.3 * i));
    if (t == steps / 2) batch.reset(n / 2), singles[n / 2].reset();
    batch.step(xp.data());
    for (int i = 0; i < n; ++i) {
      const T* ys = singles[i].step(x[i].data());
      REQUIRE_MESSAGE(std::memcmp(ys, batch.output(i), sizeof(T) * Net::out_size) == 0,
                      "instance " << i << " of " << n << ", step " << t);
    }
  }
}

template <class Net>
void check_all_counts(const io::TensorTable& table) {
  for (int n : {1, 2, 3, 4, 5, 8, 9, 17}) check_equal_to_singles<Net>(table, n);
}

}  // namespace

TEST_CASE("NetworkBatch of a 3-layer GRU equals separate instances bit for bit (float, double, f16, q8)") {
  const io::TensorTable t = gru_table();
  check_all_counts<GruStack<float, float>>(t);
  check_all_counts<GruStack<double, double>>(t);
  check_all_counts<GruStack<float, nn::f16>>(t);
  check_all_counts<GruStack<float, nn::q8>>(t);
}

TEST_CASE("NetworkBatch of an MLP equals separate instances bit for bit (float, double, f16, q8)") {
  const io::TensorTable t = mlp_table();
  check_all_counts<Mlp<float, float>>(t);
  check_all_counts<Mlp<double, double>>(t);
  check_all_counts<Mlp<float, nn::f16>>(t);
  check_all_counts<Mlp<float, nn::q8>>(t);
}

template <class Net>
void check_batch_never_allocates(const io::TensorTable& table) {
  auto w = weights_from_table<Net>(table, "test");
  nn::NetworkBatch<Net> batch(w, nn::kBatchMax);
  std::vector<std::vector<float>> x(nn::kBatchMax, std::vector<float>(Net::in_size, 0.5f));
  for (int i = 0; i < nn::kBatchMax; ++i) x[i][i % Net::in_size] = 0.1f * static_cast<float>(i);
  std::vector<const float*> xp;
  for (auto& v : x) xp.push_back(v.data());
  double sink = 0;
  {
    AllocationCounter c;
    for (int t = 0; t < 200; ++t) {
      batch.step(xp.data());
      sink += batch.output(t % nn::kBatchMax)[0];
      if (t == 100) batch.reset();
    }
    CHECK(c.count() == 0);
  }
  CHECK(std::isfinite(sink));
}

TEST_CASE("NetworkBatch steps never allocate; sizes outside 1..kBatchMax are refused at construction") {
  // float, and q8 (the batched int8 kernels: the build's or the CPU's run-time upgrade, nn/int8.hpp)
  check_batch_never_allocates<GruStack<float, float>>(gru_table());
  check_batch_never_allocates<GruStack<float, nn::q8>>(gru_table());
  check_batch_never_allocates<Mlp<float, nn::q8>>(mlp_table());
  using Net = GruStack<float, float>;
  auto w = weights_from_table<Net>(gru_table(), "test");
  CHECK_THROWS_AS(nn::NetworkBatch<Net>(w, 0), std::invalid_argument);
  CHECK_THROWS_AS(nn::NetworkBatch<Net>(w, nn::kBatchMax + 1), std::invalid_argument);
}
