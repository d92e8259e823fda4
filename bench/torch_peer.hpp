// The papers' networks in LibTorch (one thread, inference mode), stepped one frame at a time with
// their recurrent state carried over, as the peer the sparsebody benchmarks are compared against.
// Lives in its own translation unit (torch_peer.cpp) so LibTorch headers stay out of the others.
#pragma once
#include <memory>
#include <vector>

namespace sparsebody_bench {

struct TorchPeer {
  virtual ~TorchPeer() = default;
  virtual void step() = 0;  // one frame on a fixed input
};

void torch_init_single_thread();
std::unique_ptr<TorchPeer> torch_lobstr(int hidden, int latent);
std::unique_ptr<TorchPeer> torch_n3p_predictor(int in, int hidden, int out);
std::unique_ptr<TorchPeer> torch_mlp(const std::vector<int>& sizes, bool tanh_everywhere);

}  // namespace sparsebody_bench
