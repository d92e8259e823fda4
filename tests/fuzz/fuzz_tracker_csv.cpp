// Tracker CSV sessions: any byte string either parses into frames or raises one LoadError naming
// the line and field.
#include <cstdint>
#include <sstream>
#include <string>

#include "sparsebody/core/error.hpp"
#include "sparsebody/recordings/tracker_csv.hpp"

#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    const auto frames = sparsebody::recordings::parse_tracker_csv(in, "fuzz.csv");
    sparsebody_fuzz::consume(frames.empty() ? 0.0 : frames.back().time);
  } catch (const sparsebody::LoadError& e) {
    sparsebody_fuzz::check_message(e.what());
  }
  return 0;
}
