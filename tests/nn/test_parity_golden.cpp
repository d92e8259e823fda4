// Parity with PyTorch on the committed golden vectors (tests/golden, written by
// `/usr/bin/python3 -m weights_tool golden small tests/golden`): 1000-step stateful sequences,
// float <= 1e-5 vs torch float32, double <= 1e-12 vs torch float64. Runs without torch.
#include "nn/golden.hpp"
#include "nn/golden_nets.hpp"

using namespace sparsebody_test;
static const std::string kDir = SPARSEBODY_TEST_DATA_DIR;

TEST_CASE("parity: every stateless layer kind (Linear +/- bias, ReLU, tanh, sigmoid, ELU, softmax)") {
  check_parity<ZooNet>(kDir, "zoo", "sequential");
}
TEST_CASE("parity: 2-layer GRU stack == torch.nn.GRU(num_layers=2), sizes not multiples of the SIMD width") {
  check_parity<GruStackNet>(kDir, "gru_stack", "gru");
}
TEST_CASE("parity: LoBSTr network shape with input/output normalisation") {
  check_parity<LoBSTrSmall>(kDir, "lobstr_small", "lobstr");
}
TEST_CASE("parity: Neural3Points predictor shape (encoder, 3-layer GRU, decoder)") {
  check_parity<N3PSmall>(kDir, "n3p_small", "n3p_signal");
}
TEST_CASE("parity: Neural3Points policy shape (ReLU MLP)") {
  check_parity<PolicySmall>(kDir, "policy_small", "n3p_policy");
}
TEST_CASE("parity: tanh MLP (QuestSim policy shape)") {
  check_parity<MlpTanhSmall>(kDir, "mlp_tanh_small", "mlp");
}
