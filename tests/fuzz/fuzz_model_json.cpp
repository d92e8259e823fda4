// Dynamics model JSON: any byte string either gives a validated model (which then survives a
// simulation step) or raises one LoadError with a one-line bounded message.
#include <cstdint>
#include <string>

#include "sparsebody/core/error.hpp"
#include "sparsebody/dynamics/model_json.hpp"
#include "sparsebody/dynamics/simulator.hpp"

#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const auto m = sparsebody::dynamics::parse_model_json<double, 24, 72>(text, "fuzz.model.json");
    sparsebody::dynamics::Simulator<double, 24, 72> sim(m);
    sim.step(1.0 / 120);  // any status is fine; it must not crash
    sparsebody_fuzz::consume(sim.q()(0));
  } catch (const sparsebody::LoadError& e) {
    sparsebody_fuzz::check_message(e.what());
  }
  return 0;
}
