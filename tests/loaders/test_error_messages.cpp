// Every load error is one line that names the file and the place, with at most ~200 characters of
// the offending content, and a missing file says that it is missing.
#include <doctest/doctest.h>

#include <fstream>
#include <sstream>
#include <string>

#include "loader_test.hpp"
#include "sparsebody/core/error.hpp"
#include "sparsebody/io/weights_json.hpp"
#include "sparsebody/recordings/bvh.hpp"
#include "sparsebody/recordings/tracker_csv.hpp"

using namespace sparsebody;

namespace {

using loader_test::load_error;

bool one_bounded_line(const std::string& s) {
  return !s.empty() && s.size() <= 420 && s.find('\n') == std::string::npos && s.find('\r') == std::string::npos;
}

}  // namespace

TEST_CASE("excerpt keeps short text, flattens control characters and cuts long text in the middle") {
  CHECK(excerpt("abc") == "abc");
  CHECK(excerpt("a\nb\tc") == "a b c");
  const std::string cut = excerpt(std::string(1000, 'x') + "END", 200);
  CHECK(cut.size() < 240);
  CHECK(cut.find("[... 803 characters ...]") != std::string::npos);
  CHECK(cut.substr(cut.size() - 3) == "END");
}

TEST_CASE("a truncated weights file gives one short line naming the file, not its base64") {
  std::ifstream f(std::string(SPARSEBODY_WEIGHTS_DIR) + "/lobstr_compact.weights.json");
  REQUIRE(f);
  std::stringstream ss;
  ss << f.rdbuf();
  const std::string text = ss.str().substr(0, ss.str().size() / 2);  // cut inside a tensor's base64
  const std::string e = load_error([&] { io::parse_weights(text, "lobstr_compact.weights.json"); });
  INFO(e);
  CHECK(one_bounded_line(e));
  CHECK(e.rfind("lobstr_compact.weights.json: not valid JSON (truncated or corrupt?) at byte ", 0) == 0);
}

TEST_CASE("a missing file says so") {
  const std::string e = load_error([] { io::read_weights_file("/nonexistent/w.json"); });
  CHECK(e == "/nonexistent/w.json: cannot open file (No such file or directory)");
  CHECK(load_error([] { recordings::read_bvh("/nonexistent/a.bvh"); }) ==
        "/nonexistent/a.bvh: cannot open file (No such file or directory)");
  CHECK(load_error([] { recordings::read_tracker_csv("/nonexistent/s.csv"); }) ==
        "/nonexistent/s.csv: cannot open file (No such file or directory)");
}

TEST_CASE("offending content is quoted in bounded excerpts") {
  // a 100 kB token where a BVH number belongs
  std::string bvh = "HIERARCHY\nROOT Hips\n{\n OFFSET " + std::string(100000, '7') + "x 0 0\n";
  std::istringstream in(bvh);
  const std::string e = load_error([&] { recordings::parse_bvh(in, "long.bvh"); });
  INFO(e);
  CHECK(one_bounded_line(e));
  CHECK(e.rfind("long.bvh: line 4: expected OFFSET x y z (3 numbers), got '777", 0) == 0);
  // a CSV field of binary garbage with newlines inside the quoted excerpt's reach
  std::string csv = recordings::tracker_csv_header() + "\n" + std::string(50000, '\x01') + ",1\n";
  std::istringstream cin(csv);
  const std::string c = load_error([&] { recordings::parse_tracker_csv(cin, "s.csv"); });
  INFO(c);
  CHECK(one_bounded_line(c));
  CHECK(c.rfind("s.csv: line 2: field 'time': expected a number, got '", 0) == 0);
  // a weights tensor whose name is 10 kB long
  const std::string doc = R"({"format": "sparsebody-weights", "version": 1, "kind": "mlp", "meta": {"input_size": 1, "output_size": 1}, "tensors": {")" +
                          std::string(10000, 'n') + R"(": {"shape": [2], "data": [1]}}})";
  const std::string w = load_error([&] { io::parse_weights(doc, "names.json"); });
  CHECK(one_bounded_line(w));
  CHECK(w.rfind("names.json: tensor 'nnn", 0) == 0);
}
