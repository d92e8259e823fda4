// Builds TensorTables with random values in C++, for tests that need weights without a file.
#pragma once
#include <random>
#include <string>

#include "sparsebody/io/tensor_table.hpp"

namespace sparsebody_test {

inline void add_random(sparsebody::io::TensorTable& t, const std::string& name, std::vector<std::int64_t> shape,
                       std::mt19937& rng, double scale = 0.3) {
  std::normal_distribution<double> d(0.0, scale);
  sparsebody::io::Tensor x;
  x.shape = shape;
  std::size_t n = 1;
  for (auto s : shape) n *= static_cast<std::size_t>(s);
  x.values.resize(n);
  for (auto& v : x.values) v = static_cast<float>(d(rng));  // float-representable: same in float and double
  t.tensors()[name] = std::move(x);
}

// Tensors of torch.nn.GRU(in, h, num_layers) under `prefix`.
inline void add_gru(sparsebody::io::TensorTable& t, const std::string& prefix, int in, int h, int layers, std::mt19937& rng) {
  for (int k = 0; k < layers; ++k) {
    const std::string s = "_l" + std::to_string(k);
    add_random(t, prefix + "weight_ih" + s, {3 * h, k == 0 ? in : h}, rng);
    add_random(t, prefix + "weight_hh" + s, {3 * h, h}, rng);
    add_random(t, prefix + "bias_ih" + s, {3 * h}, rng);
    add_random(t, prefix + "bias_hh" + s, {3 * h}, rng);
  }
}
inline void add_linear(sparsebody::io::TensorTable& t, const std::string& prefix, int in, int out, std::mt19937& rng,
                       double scale = 0.3) {
  add_random(t, prefix + "weight", {out, in}, rng, scale);
  add_random(t, prefix + "bias", {out}, rng, scale);
}

}  // namespace sparsebody_test
