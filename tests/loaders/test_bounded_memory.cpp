// No loader allocates more than the bytes present justify: frame counts, tensor shapes and body
// counts claimed by a file are checked against what it holds before anything is reserved.
#include <doctest/doctest.h>

#include <sstream>
#include <string>

#include "loader_test.hpp"
#include "support/alloc_counter.hpp"
#include "sparsebody/core/error.hpp"
#include "sparsebody/dynamics/model_json.hpp"
#include "sparsebody/io/weights_json.hpp"
#include "sparsebody/recordings/bvh.hpp"
#include "sparsebody/recordings/tracker_csv.hpp"

using namespace sparsebody;

namespace {

const char* kTinyBvh =
    "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
    "  End Site\n  {\n    OFFSET 0 10 0\n  }\n}\nMOTION\nFrames: %s\nFrame Time: 0.0333333\n"
    "0 90 0 0 0 0\n0 90 0 1 0 0\n0 90 0 2 0 0\n";

std::string bvh_claiming(const char* frames) {
  char buf[512];
  std::snprintf(buf, sizeof buf, kTinyBvh, frames);
  return buf;
}

using loader_test::load_error;

constexpr std::size_t kSmall = 64 * 1024;  // what a few-hundred-byte file may justify, generously

}  // namespace

TEST_CASE("a BVH whose header claims far more frames than it holds fails at its end, without reserving them") {
  sparsebody_test::LargestAllocation largest;
  const std::string e = load_error([] {
    std::istringstream in(bvh_claiming("999999999"));
    recordings::parse_bvh(in, "huge.bvh");
  });
  CHECK(e == "huge.bvh: line 16: expected 999999999 frames, found 3");
  CHECK(largest.bytes() < kSmall);
  std::istringstream ok(bvh_claiming("3"));
  CHECK(recordings::parse_bvh(ok, "ok.bvh").frames == 3);
}

TEST_CASE("a BVH frame count outside the int range is refused") {
  for (const char* n : {"1e12", "3000000000", "-1", "2.5", "nan"}) {
    INFO(n);
    const std::string e = load_error([&] {
      std::istringstream in(bvh_claiming(n));
      recordings::parse_bvh(in, "count.bvh");
    });
    CHECK(e.rfind("count.bvh: line 12: expected", 0) == 0);
  }
}

TEST_CASE("a weights tensor whose shape is larger than its data is refused before any allocation") {
  sparsebody_test::LargestAllocation largest;
  const std::string doc = R"({"format": "sparsebody-weights", "version": 1, "kind": "mlp", "meta": {"input_size": 1, "output_size": 1},
    "tensors": {"w": {"shape": [100000, 100000], "dtype": "float32", "data": "AAAAAAAAAAA="}}})";
  CHECK(load_error([&] { io::parse_weights(doc, "big.json"); }) ==
        "big.json: tensor 'w': shape [100000, 100000] is larger than its data");
  CHECK(largest.bytes() < kSmall);
}

TEST_CASE("a weights tensor shape whose element count overflows is refused") {
  for (const char* data : {R"("")", "[]"}) {
    INFO(data);
    const std::string doc = std::string(R"({"format": "sparsebody-weights", "version": 1, "kind": "mlp", "meta": {"input_size": 1, "output_size": 1},
      "tensors": {"w": {"shape": [4294967296, 4294967296, 4294967296], "data": )") + data + "}}}";
    CHECK(load_error([&] { io::parse_weights(doc, "overflow.json"); }).find("is larger than its data") != std::string::npos);
  }
  // zero-sized dimensions stay legal whatever follows them
  const std::string zero = R"({"format": "sparsebody-weights", "version": 1, "kind": "mlp", "meta": {"input_size": 1, "output_size": 1},
    "tensors": {"w": {"shape": [0, 4294967296], "data": ""}}})";
  CHECK(io::parse_weights(zero, "zero.json").tensors.tensors().at("w").values.empty());
}

TEST_CASE("number-array tensors nested deeper than any shape are refused, not recursed into") {
  std::string deep = R"({"format": "sparsebody-weights", "version": 1, "kind": "mlp", "meta": {"input_size": 1, "output_size": 1}, "tensors": {"w": {"shape": [1], "data": )";
  for (int i = 0; i < 5000; ++i) deep += '[';
  deep += '1';
  for (int i = 0; i < 5000; ++i) deep += ']';
  deep += "}}}";
  CHECK(load_error([&] { io::parse_weights(deep, "deep.json"); }) ==
        "deep.json: tensor 'w': 'data' nests arrays deeper than 16 levels");
}

TEST_CASE("a model file with more bodies than the model's bound is refused without allocating for them") {
  std::string m = R"({"name": "many", "gravity": [0, -9.81, 0], "bodies": [)";
  for (int i = 0; i < 40; ++i) {
    if (i) m += ",";
    m += R"({"name": "b)" + std::to_string(i) + R"(", "parent": )" + (i ? "\"b" + std::to_string(i - 1) + "\"" : "null") +
         R"(, "joint": ")" + (i ? "spherical" : "free") +
         R"(", "pos": [0, 0.1, 0], "quat": [1, 0, 0, 0], "mass": 1, "com": [0, 0, 0], "inertia": [0.01, 0.01, 0.01, 0, 0, 0]})";
  }
  m += "]}";
  sparsebody_test::LargestAllocation largest;
  const std::string e = load_error([&] { dynamics::parse_model_json<double, 24, 72>(m, "many.json"); });
  CHECK(e.rfind("many.json: ", 0) == 0);
  CHECK(e.find("24") != std::string::npos);  // names the bound
  CHECK(largest.bytes() < 4 * m.size() + kSmall);
}
