// The whole chain at the papers' sizes: PyTorch -> export -> C++ -> compare. The weights and golden
// vectors are generated at test time by `weights_tool golden paper <dir>` (CTest fixture), since
// they are megabytes; the directory comes from SPARSEBODY_PAPER_GOLDEN_DIR.
#include <cstdlib>

#include "nn/golden.hpp"
#include "nn/golden_nets.hpp"

using namespace sparsebody_test;

static std::string dir() {
  const char* d = std::getenv("SPARSEBODY_PAPER_GOLDEN_DIR");
  REQUIRE_MESSAGE(d != nullptr, "SPARSEBODY_PAPER_GOLDEN_DIR not set (run through ctest)");
  return d;
}

TEST_CASE("paper parity: LoBSTr GRU 37->1024, latent 128") { check_parity<LoBSTr1024>(dir(), "lobstr_1024", "lobstr"); }
TEST_CASE("paper parity: LoBSTr GRU 37->256, latent 128") { check_parity<LoBSTr256>(dir(), "lobstr_256", "lobstr"); }
TEST_CASE("paper parity: N3P Gsig (hidden 64)") { check_parity<N3PSignal>(dir(), "n3p_signal", "n3p_signal"); }
TEST_CASE("paper parity: N3P Glo (hidden 128)") { check_parity<N3PLower>(dir(), "n3p_lower", "n3p_lower"); }
TEST_CASE("paper parity: N3P Gup (hidden 128)") { check_parity<N3PUpper>(dir(), "n3p_upper", "n3p_upper"); }
TEST_CASE("paper parity: N3P control policy") { check_parity<N3PPolicy>(dir(), "n3p_policy", "n3p_policy"); }
TEST_CASE("paper parity: QuestSim policy 475-400-300-200-33 tanh") {
  check_parity<QuestSimPolicy>(dir(), "questsim_policy", "questsim_policy");
}
