// Uses the public headers the way an engine would: a network type, weights from a file, one step.
#include <cstdio>

#include <sparsebody/networks/policy_nets.hpp>
#include <sparsebody/nn/network.hpp>

int main(int argc, char** argv) {
  using Net = sparsebody::networks::N3PPolicyNet<float, 50, 9, 32>;
  if (argc < 2) return 2;
  try {
    auto w = sparsebody::nn::NetworkWeights<Net>::load(argv[1], "n3p_policy");
    sparsebody::nn::Network<Net> net(w);
    float x[50] = {};
    const float* y = net.step(x);
    std::printf("consumer ok: y[0] = %g\n", double(y[0]));
  } catch (const sparsebody::LoadError& e) {
    std::printf("load error: %s\n", e.what());
    return 1;
  }
  return 0;
}
