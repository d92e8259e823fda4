#include "torch_peer.hpp"

#include <torch/torch.h>

namespace sparsebody_bench {

void torch_init_single_thread() {
  torch::set_num_threads(1);
  torch::set_num_interop_threads(1);
}

namespace {
struct LoBSTr : TorchPeer {
  torch::nn::GRU gru;
  torch::nn::Linear latent, pose, contact;
  torch::Tensor x, h;
  LoBSTr(int H, int L)
      : gru(torch::nn::GRUOptions(37, H)), latent(H, L), pose(L, 48), contact(L, 4),
        x(torch::randn({1, 1, 37})), h(torch::zeros({1, 1, H})) {}
  void step() override {
    torch::InferenceMode guard;
    auto out = gru->forward(x, h);
    h = std::get<1>(out);
    auto l = torch::relu(latent->forward(std::get<0>(out)));
    auto p = pose->forward(l);
    auto c = torch::softmax(contact->forward(l).view({1, 1, 2, 2}), -1);
    (void)p.data_ptr<float>();
    (void)c.data_ptr<float>();
  }
};
struct N3P : TorchPeer {
  torch::nn::Linear enc, dec;
  torch::nn::GRU gru;
  torch::Tensor x, h;
  N3P(int in, int H, int out)
      : enc(in, H), dec(H, out), gru(torch::nn::GRUOptions(H, H).num_layers(3)), x(torch::randn({1, 1, in})),
        h(torch::zeros({3, 1, H})) {}
  void step() override {
    torch::InferenceMode guard;
    auto out = gru->forward(enc->forward(x), h);
    h = std::get<1>(out);
    auto y = dec->forward(std::get<0>(out));
    (void)y.data_ptr<float>();
  }
};
struct MLP : TorchPeer {
  std::vector<torch::nn::Linear> layers;
  bool tanh_all;
  torch::Tensor x;
  MLP(const std::vector<int>& s, bool t) : tanh_all(t), x(torch::randn({1, s[0]})) {
    for (std::size_t i = 0; i + 1 < s.size(); ++i) layers.emplace_back(s[i], s[i + 1]);
  }
  void step() override {
    torch::InferenceMode guard;
    torch::Tensor y = x;
    for (std::size_t i = 0; i < layers.size(); ++i) {
      y = layers[i]->forward(y);
      if (tanh_all) y = torch::tanh(y);
      else if (i + 1 < layers.size()) y = torch::relu(y);
    }
    (void)y.data_ptr<float>();
  }
};
}  // namespace

std::unique_ptr<TorchPeer> torch_lobstr(int hidden, int latent) { return std::make_unique<LoBSTr>(hidden, latent); }
std::unique_ptr<TorchPeer> torch_n3p_predictor(int in, int hidden, int out) {
  return std::make_unique<N3P>(in, hidden, out);
}
std::unique_ptr<TorchPeer> torch_mlp(const std::vector<int>& sizes, bool tanh_everywhere) {
  return std::make_unique<MLP>(sizes, tanh_everywhere);
}

}  // namespace sparsebody_bench
