// Proves that stepping, resetting and reading every layer and network does not touch the heap.
#include "support/alloc_counter.hpp"


#include <doctest/doctest.h>

#include "nn/golden.hpp"
#include "nn/golden_nets.hpp"
#include "nn/random_tables.hpp"

using namespace sparsebody_test;
static const std::string kDir = SPARSEBODY_TEST_DATA_DIR;

template <class Net>
void check_no_alloc(std::shared_ptr<const sparsebody::nn::NetworkWeights<Net>> w, int steps = 1000) {
  using T = typename Net::scalar;
  sparsebody::nn::Network<Net> net(w);  // construction may allocate (state), steps may not
  std::vector<T> x(Net::in_size);
  double sink = 0;
  AllocationCounter c;
  for (int t = 0; t < steps; ++t) {
    for (int i = 0; i < Net::in_size; ++i) x[i] = static_cast<T>(golden_input(t, i));
    sink += double(net.step(x.data())[0]);
    if (t % 3 == 0) sink += double(net.step_guarded(x.data()) == sparsebody::nn::NetStatus::Ok);
    if (t == steps / 2) net.reset();
  }
  const long long n = c.count();
  CHECK(n == 0);
  CHECK(std::isfinite(sink));
}

template <template <typename> class NetOf>
void check_golden_no_alloc(const std::string& name, const std::string& kind) {
  check_no_alloc(sparsebody::nn::NetworkWeights<NetOf<float>>::load(kDir + "/" + name + ".weights.json", kind));
  check_no_alloc(sparsebody::nn::NetworkWeights<NetOf<double>>::load(kDir + "/" + name + ".weights.json", kind));
}

TEST_CASE("the counter counts") {
  AllocationCounter c;
  auto* p = new int(3);
  delete p;
  CHECK(c.count() == 1);
}
TEST_CASE("zero allocations: every layer kind") { check_golden_no_alloc<ZooNet>("zoo", "sequential"); }
TEST_CASE("zero allocations: GRU stack") { check_golden_no_alloc<GruStackNet>("gru_stack", "gru"); }
TEST_CASE("zero allocations: LoBSTr with normalisation") { check_golden_no_alloc<LoBSTrSmall>("lobstr_small", "lobstr"); }
TEST_CASE("zero allocations: N3P predictor") { check_golden_no_alloc<N3PSmall>("n3p_small", "n3p_signal"); }
TEST_CASE("zero allocations: policies") {
  check_golden_no_alloc<PolicySmall>("policy_small", "n3p_policy");
  check_golden_no_alloc<MlpTanhSmall>("mlp_tanh_small", "mlp");
}
TEST_CASE("zero allocations: LoBSTr with float16 weight storage") {
  check_no_alloc(sparsebody::nn::NetworkWeights<sparsebody::networks::LoBSTrNet<float, 40, 24, 37, sparsebody::nn::f16>>::load(
      kDir + "/lobstr_small.weights.json", "lobstr"));
}
TEST_CASE("zero allocations: LoBSTr and the QuestSim policy with int8 weight storage") {
  check_no_alloc(sparsebody::nn::NetworkWeights<sparsebody::networks::LoBSTrNet<float, 40, 24, 37, sparsebody::nn::q8>>::load(
      kDir + "/lobstr_small.weights.json", "lobstr"));
  check_no_alloc(weights_from_table<sparsebody::networks::LoBSTrNet<float, 1024, 128, 37, sparsebody::nn::q8>>(random_lobstr_table(1024, 128, 1), "lobstr"), 100);
}
TEST_CASE("zero allocations: paper-size LoBSTr 37->1024") {
  check_no_alloc(weights_from_table<LoBSTr1024<float>>(random_lobstr_table(1024, 128, 1), "lobstr"), 100);
}
