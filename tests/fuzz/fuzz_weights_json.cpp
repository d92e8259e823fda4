// Weights JSON (base64 and number-array tensors): any byte string either loads into a network or
// raises one LoadError whose message is one line of bounded length; never a crash, a leak, a
// sanitizer report or an allocation the input does not justify (libFuzzer's -rss_limit_mb).
#include <cstdint>
#include <cstdlib>
#include <string>

#include "sparsebody/core/error.hpp"
#include "sparsebody/networks/lobstr_net.hpp"
#include "sparsebody/nn/network.hpp"

#include "fuzz_common.hpp"

using Net = sparsebody::networks::LoBSTrNet<float, 16, 8, 37>;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    // the document parser, then (when the document is one) binding it to a network
    auto doc = sparsebody::io::parse_weights(text, "fuzz.weights.json");
    const auto w = sparsebody::nn::NetworkWeights<Net>::from_document(std::move(doc), "lobstr");
    sparsebody::nn::Network<Net> net(w);
    float x[37] = {};
    const float* y = net.step(x);
    sparsebody_fuzz::consume(y[0]);
  } catch (const sparsebody::LoadError& e) {
    sparsebody_fuzz::check_message(e.what());
  }
  return 0;
}
