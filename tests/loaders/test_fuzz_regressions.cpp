// Every input the fuzzers (tests/fuzz) found a crash with is kept in tests/fuzz/regressions/ as
// <harness>-<what>; here each goes through its loader again, in the normal build: it must load or
// raise a LoadError (one bounded line), never anything else.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "sparsebody/core/error.hpp"
#include "sparsebody/dynamics/model_json.hpp"
#include "sparsebody/io/weights_json.hpp"
#include "sparsebody/recordings/bvh.hpp"
#include "sparsebody/recordings/tracker_csv.hpp"

using namespace sparsebody;

TEST_CASE("the fuzzers' crash inputs load or fail with a LoadError") {
  const std::filesystem::path dir = std::filesystem::path(SPARSEBODY_SOURCE_DIR) / "tests" / "fuzz" / "regressions";
  int n = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    INFO(name);
    std::ifstream f(e.path(), std::ios::binary);
    std::stringstream ss;
    ss << f.rdbuf();
    const std::string text = ss.str();
    auto load = [&] {
      if (name.rfind("model_json-", 0) == 0) dynamics::parse_model_json<double, 24, 72>(text, name);
      else if (name.rfind("weights_json-", 0) == 0) io::parse_weights(text, name);
      else if (name.rfind("bvh-", 0) == 0) { std::istringstream in(text); recordings::parse_bvh(in, name); }
      else if (name.rfind("tracker_csv-", 0) == 0) { std::istringstream in(text); recordings::parse_tracker_csv(in, name); }
      else FAIL("unknown harness prefix");
    };
    try {
      load();
    } catch (const LoadError& err) {
      const std::string m = err.what();
      CHECK(m.find('\n') == std::string::npos);
      CHECK(m.size() <= 420);
    }
    ++n;
  }
  CHECK(n >= 1);
}
