// Builds TensorTables with random values in C++, for tests that need weights without a file.
#pragma once
#include <random>
#include <string>

#include "sparsebody/io/tensor_table.hpp"
#include "sparsebody/io/weights_json.hpp"
#include "sparsebody/nn/network.hpp"

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

// Tensors of a LoBSTr network (weights_tool nets.LoBSTrNet) with hidden H and latent L; only the GRU
// (under "gru.") when gru_only.
inline sparsebody::io::TensorTable random_lobstr_table(int H, int L, unsigned seed, bool gru_only = false) {
  std::mt19937 rng(seed);
  sparsebody::io::TensorTable t("random");
  add_gru(t, "gru.", 37, H, 1, rng);
  if (!gru_only) {
    add_linear(t, "latent.", H, L, rng);
    add_linear(t, "pose.", L, 48, rng);
    add_linear(t, "contact.", L, 4, rng);
  }
  return t;
}

// Loads Net's weights from an in-memory table, as the file loader would (all checks included).
template <class Net>
std::shared_ptr<const sparsebody::nn::NetworkWeights<Net>> weights_from_table(sparsebody::io::TensorTable t,
                                                                              const char* kind) {
  sparsebody::io::WeightsDocument doc;
  doc.info.source = t.source();
  doc.tensors = std::move(t);
  doc.info.kind = kind;
  doc.info.input_size = Net::in_size;
  doc.info.output_size = Net::out_size;
  return sparsebody::nn::NetworkWeights<Net>::from_document(std::move(doc), kind);
}

}  // namespace sparsebody_test
