// N instances of one network sharing one weight set, stepped together (e.g. several avatars in a
// scene): each weight matrix is streamed once per frame for all of them instead of once per
// instance (float and f16 storage; q8 with a dot-product kernel, built in or the run-time upgrade:
// groups of 4 (AVX-512 VNNI, NEON dot product) or 2 (AVX-VNNI) instances, and one product per
// instance elsewhere: int8.hpp gemv_batch).
//
//   auto weights = nn::NetworkWeights<Net>::load("model.json", "lobstr");
//   nn::NetworkBatch<Net> crowd(weights, 16);        // allocates the 16 states once
//   crowd.step(inputs);                              // inputs[i]: in_size values of instance i
//   const float* y3 = crowd.output(3);               // = what a Network<Net> fed instance 3's inputs gives
//
// Every instance's outputs equal a Network<Net> step on the same inputs bit for bit (same products,
// same FMA order; tests/nn/test_batch.cpp). Works for nets built from Dense, Activation, GRU, Named
// and Sequential (MLPs, GRU stacks); step() never allocates, throws or locks.
#pragma once
#include <memory>
#include <stdexcept>
#include <string>

#include "sparsebody/nn/network.hpp"

namespace sparsebody::nn {

template <class Net>
class NetworkBatch {
 public:
  using T = typename Net::scalar;
  using State = typename Net::State;
  static constexpr int in_size = Net::in_size;
  static constexpr int out_size = Net::out_size;

  // n instances, 1 <= n <= kBatchMax (std::invalid_argument otherwise; construction time only).
  NetworkBatch(std::shared_ptr<const NetworkWeights<Net>> weights, int n) : weights_(std::move(weights)), n_(n) {
    if (n < 1 || n > kBatchMax)
      throw std::invalid_argument("NetworkBatch: " + std::to_string(n) + " instances, expected 1.." + std::to_string(kBatchMax));
    mem_ = std::make_unique<Memory[]>(static_cast<std::size_t>(n));
  }

  int size() const noexcept { return n_; }

  // One step of every instance: x[i] holds instance i's in_size inputs. No allocation.
  void step(const T* const* x) noexcept {
    const NetworkWeights<Net>& w = *weights_;
    const T* xin[kBatchMax];
    T* y[kBatchMax];
    State* s[kBatchMax];
    for (int k = 0; k < n_; ++k) {
      T* in = mem_[k].input.data();
      if (w.input_mean()) {  // as Network::step
        for (int i = 0; i < in_size; ++i) in[i] = (x[k][i] - w.input_mean()[i]) * w.input_inv_std()[i];
      } else {
        for (int i = 0; i < in_size; ++i) in[i] = x[k][i];
      }
      xin[k] = in;
      y[k] = mem_[k].output.data();
      s[k] = &mem_[k].state;
    }
    Net::forward_batch(w.params(), s, n_, xin, y);
    if (w.output_std())
      for (int k = 0; k < n_; ++k)
        for (int i = 0; i < out_size; ++i) y[k][i] = y[k][i] * w.output_std()[i] + w.output_mean()[i];
  }

  // Outputs of instance i from the last step (out_size values).
  const T* output(int i) const noexcept { return mem_[i].output.data(); }
  State& state(int i) noexcept { return mem_[i].state; }
  void reset(int i) noexcept { Net::reset(mem_[i].state); }
  void reset() noexcept {
    for (int i = 0; i < n_; ++i) reset(i);
  }

 private:
  struct Memory {
    State state{};
    PaddedVector<T, in_size> input;
    PaddedVector<T, out_size> output;
  };
  std::shared_ptr<const NetworkWeights<Net>> weights_;
  int n_;
  std::unique_ptr<Memory[]> mem_;
};

// m Networks sharing one weight set (nets[k], each with its own state, e.g. one per avatar
// pipeline) stepped together: x[k] normalised into in[k] (in_size values), one forward_batch, the
// outputs denormalised in y[k] (out_size, padded buffers): what m Network::step calls give, bit for
// bit. The avatar batches (avatar/lobstr_batch.hpp, n3p_batch.hpp) use it. No allocation.
template <class Net>
void step_networks(Network<Net>* const* nets, int m, const typename Net::scalar* const* x, typename Net::scalar* const* in,
                   typename Net::scalar* const* y) noexcept {
  using T = typename Net::scalar;
  if (m <= 0) return;
  const NetworkWeights<Net>& w = nets[0]->weights();
  typename Net::State* s[kBatchMax];
  const T* xin[kBatchMax];
  for (int k = 0; k < m; ++k) {
    if (w.input_mean()) {  // as Network::step
      for (int i = 0; i < Net::in_size; ++i) in[k][i] = (x[k][i] - w.input_mean()[i]) * w.input_inv_std()[i];
    } else {
      for (int i = 0; i < Net::in_size; ++i) in[k][i] = x[k][i];
    }
    xin[k] = in[k];
    s[k] = &nets[k]->state();
  }
  Net::forward_batch(w.params(), s, m, xin, y);
  if (w.output_std())
    for (int k = 0; k < m; ++k)
      for (int i = 0; i < Net::out_size; ++i) y[k][i] = y[k][i] * w.output_std()[i] + w.output_mean()[i];
}

}  // namespace sparsebody::nn
