// Multi-layer GRU equal to torch.nn.GRU(In, H, num_layers=Layers) stepped one frame at a time.
//
// PyTorch semantics, per layer k (input x = previous layer's h, or the layer input for k = 0):
//   r = sigma(W_ir x + b_ir + W_hr h + b_hr)
//   z = sigma(W_iz x + b_iz + W_hz h + b_hz)
//   n = tanh (W_in x + b_in + r * (W_hn h + b_hn))     <- b_hn stays inside the reset product
//   h' = (1 - z) * n + z * h
// state_dict: weight_ih_l{k} [3H, in_k], weight_hh_l{k} [3H, H], bias_ih_l{k}, bias_hh_l{k} [3H],
// gate blocks stacked in the order r, z, n.
//
// At load each gate block is re-placed at a batch-aligned offset (0, Hp, 2Hp with Hp = padded(H)),
// so the gate update runs on aligned full batches for any H. Padding lanes compute r = z = 1/2,
// n = 0 and so keep h's padding at zero. W is the stored weight type: T, or f16 for float networks
// (half the bytes per step; biases stay in T).
#pragma once
#include <vector>

#include "sparsebody/nn/activation.hpp"
#include "sparsebody/nn/layer.hpp"

namespace sparsebody::nn {

template <typename T, int In, int H, int Layers = 1, typename W = T>
struct GRU {
  static_assert(In > 0 && H > 0 && Layers > 0, "GRU: sizes must be positive");
  using scalar = T;
  static constexpr int in_size = In;
  static constexpr int out_size = H;
  static constexpr int hidden_size = H;
  static constexpr int num_layers = Layers;
  static constexpr int Hp = padded<T>(H);

  struct LayerParams {
    PanelMatrix<T, W> w_ih;  // [3Hp, in_k] packed
    PanelMatrix<T, W> w_hh;  // [3Hp, H] packed
    const T* b_ih = nullptr;
    const T* b_hh = nullptr;
  };
  struct Params {
    LayerParams layer[Layers];
  };

  struct alignas(kBufferAlign) State {
    alignas(kBufferAlign) T h[Layers][Hp] = {};  // hidden state per layer (padding stays 0)
    alignas(kBufferAlign) T gi[3 * Hp] = {};     // W_ih x + b_ih, gates r|z|n
    alignas(kBufferAlign) T gh[3 * Hp] = {};     // W_hh h + b_hh
    void reset() noexcept {
      for (auto& l : h)
        for (T& v : l) v = T(0);
    }
    T* hidden(int layer) noexcept { return h[layer]; }
    const T* hidden(int layer) const noexcept { return h[layer]; }
  };

  static void bind(Params& p, ParamBinder<T>& b, const std::string& prefix) {
    std::vector<int> row_map(3 * H);  // gate g row i -> g*Hp + i
    for (int g = 0; g < 3; ++g)
      for (int i = 0; i < H; ++i) row_map[g * H + i] = g * Hp + i;
    for (int k = 0; k < Layers; ++k) {
      const std::string s = "_l" + std::to_string(k);
      const int in_k = k == 0 ? In : H;
      p.layer[k].w_ih = b.template matrix<W>(prefix + "weight_ih" + s, 3 * H, in_k, 3 * Hp, row_map.data());
      p.layer[k].w_hh = b.template matrix<W>(prefix + "weight_hh" + s, 3 * H, H, 3 * Hp, row_map.data());
      p.layer[k].b_ih = b.vector(prefix + "bias_ih" + s, 3 * H, 3 * Hp, row_map.data());
      p.layer[k].b_hh = b.vector(prefix + "bias_hh" + s, 3 * H, 3 * Hp, row_map.data());
    }
  }

  static void forward(const Params& p, State& s, const T* x, T* y) noexcept {
    const T* in = x;
    for (int k = 0; k < Layers; ++k) {
      const LayerParams& lp = p.layer[k];
      gemv(lp.w_ih, in, lp.b_ih, s.gi);     // W_i{r,z,n} x + b_i{r,z,n}
      gemv(lp.w_hh, s.h[k], lp.b_hh, s.gh);  // W_h{r,z,n} h + b_h{r,z,n}
      gate_update(s, k);
      in = s.h[k];
    }
    copy_out(s, y);
  }

  // n instances at once (nn/batch.hpp): each weight matrix is streamed once for all of them, and
  // every instance gets exactly forward()'s result (same products, same gate code).
  static void forward_batch(const Params& p, State* const* s, int n, const T* const* x, T* const* y) noexcept {
    const T* in[kBatchMax];
    const T* h[kBatchMax];
    T* gi[kBatchMax];
    T* gh[kBatchMax];
    for (int i = 0; i < n; ++i) in[i] = x[i], gi[i] = s[i]->gi, gh[i] = s[i]->gh;
    for (int k = 0; k < Layers; ++k) {
      const LayerParams& lp = p.layer[k];
      for (int i = 0; i < n; ++i) h[i] = s[i]->h[k];
      gemv_batch(lp.w_ih, n, in, lp.b_ih, gi);
      gemv_batch(lp.w_hh, n, h, lp.b_hh, gh);
      for (int i = 0; i < n; ++i) gate_update(*s[i], k), in[i] = s[i]->h[k];
    }
    for (int i = 0; i < n; ++i) copy_out(*s[i], y[i]);
  }

  static void reset(State& s) noexcept { s.reset(); }

 private:
  // h_k from the gate pre-activations in s.gi / s.gh.
  static void gate_update(State& s, int k) noexcept {
    using B = Batch<T>;
    T* h = s.h[k];
    for (int i = 0; i < Hp; i += kLanes<T>) {
      const B r = sigmoid<T>(B::load_aligned(s.gi + i) + B::load_aligned(s.gh + i));
      const B z = sigmoid<T>(B::load_aligned(s.gi + Hp + i) + B::load_aligned(s.gh + Hp + i));
      const B n = xsimd::tanh(xsimd::fma(r, B::load_aligned(s.gh + 2 * Hp + i), B::load_aligned(s.gi + 2 * Hp + i)));
      const B hp = B::load_aligned(h + i);
      xsimd::fma(z, hp - n, n).store_aligned(h + i);  // (1 - z) n + z h = n + z (h - n)
    }
  }
  static void copy_out(const State& s, T* y) noexcept {
    for (int i = 0; i < Hp; i += kLanes<T>) Batch<T>::load_aligned(s.h[Layers - 1] + i).store_aligned(y + i);
  }
};

}  // namespace sparsebody::nn
