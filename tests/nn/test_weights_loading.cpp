// Every way a weights file can be wrong gives a LoadError naming the file and the problem;
// nothing half-loads.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <string>

#include <doctest/doctest.h>

#include "sparsebody/nn/dense.hpp"
#include "sparsebody/nn/mlp.hpp"
#include "sparsebody/nn/network.hpp"

using namespace sparsebody;
using Net = nn::MLP<float, nn::ReLU, nn::Identity, 3, 4, 2>;  // tensors 0.weight [4,3], 0.bias, 1.weight [2,4], 1.bias

static nlohmann::json valid_doc() {
  nlohmann::json j;
  j["format"] = "sparsebody-weights";
  j["version"] = 1;
  j["kind"] = "mlp";
  j["meta"] = {{"input_size", 3}, {"output_size", 2}, {"frame_rate", 30}};
  j["tensors"]["0.weight"] = {{"shape", {4, 3}}, {"data", {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}}}};
  j["tensors"]["0.bias"] = {{"shape", {4}}, {"data", {0, 0, 0, -1}}};
  j["tensors"]["1.weight"] = {{"shape", {2, 4}}, {"data", {1, 2, 3, 4, -1, -1, -1, -1}}};  // flat also accepted
  j["tensors"]["1.bias"] = {{"shape", {2}}, {"data", {0.5, 0.25}}};
  return j;
}

static std::string load_error(const std::string& text, const std::string& kind = "mlp") {
  try {
    nn::NetworkWeights<Net>::from_string(text, kind, "model.json");
  } catch (const LoadError& e) {
    return e.what();
  }
  return "";
}
static std::string load_error(const nlohmann::json& j, const std::string& kind = "mlp") { return load_error(j.dump(), kind); }
static std::string load_error(const char* text) { return load_error(std::string(text)); }

static std::string b64(const std::string& bytes) {
  static const char* a = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    unsigned v = (unsigned char)bytes[i] << 16 | (unsigned char)bytes[i + 1] << 8 | (unsigned char)bytes[i + 2];
    for (int k = 3; k >= 0; --k) out += a[(v >> (6 * k)) & 63];
  }
  if (i < bytes.size()) {
    unsigned v = (unsigned char)bytes[i] << 16 | (i + 1 < bytes.size() ? (unsigned char)bytes[i + 1] << 8 : 0);
    out += a[(v >> 18) & 63];
    out += a[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? a[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}
static std::string floats(std::initializer_list<float> v) {
  std::string s(v.size() * 4, '\0');
  std::size_t k = 0;
  for (float f : v) std::memcpy(&s[4 * k++], &f, 4);
  return s;
}

TEST_CASE("a valid file loads and computes; list and base64 encodings agree") {
  auto w = nn::NetworkWeights<Net>::from_string(valid_doc().dump(), "mlp", "model.json");
  nn::Network<Net> n(w);
  const float x[3] = {1, 2, 3};
  const float* y = n.step(x);
  // hidden = relu([1, 2, 3, 5]) ; y0 = 1 + 4 + 9 + 20 + 0.5, y1 = -11 + 0.25
  CHECK(y[0] == doctest::Approx(34.5));
  CHECK(y[1] == doctest::Approx(-10.75));
  CHECK(w->info().frame_rate == 30);
  auto j = valid_doc();
  j["tensors"]["1.bias"] = {{"shape", {2}}, {"dtype", "float32"}, {"data", b64(floats({0.5f, 0.25f}))}};
  j["tensors"]["0.bias"] = {{"shape", {4}}, {"dtype", "float64"},
                            {"data", b64(std::string("\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0", 24) +
                                         std::string("\0\0\0\0\0\0\xf0\xbf", 8))}};  // -1.0
  nn::Network<Net> n2(nn::NetworkWeights<Net>::from_string(j.dump(), "mlp"));
  const float* y2 = n2.step(x);
  CHECK(y2[0] == y[0]);
  CHECK(y2[1] == y[1]);
}

TEST_CASE("missing tensor") {
  auto j = valid_doc();
  j["tensors"].erase("1.bias");
  CHECK(load_error(j) == "model.json: missing tensor '1.bias' (expected shape [2])");
}
TEST_CASE("unexpected tensor") {
  auto j = valid_doc();
  j["tensors"]["2.weight"] = {{"shape", {1}}, {"data", {1}}};
  CHECK(load_error(j).find("unexpected tensor(s) '2.weight'") != std::string::npos);
}
TEST_CASE("wrong shape names tensor, expected and got") {
  auto j = valid_doc();
  j["tensors"]["0.weight"] = {{"shape", {3, 4}}, {"data", std::vector<double>(12, 0.0)}};
  CHECK(load_error(j) == "model.json: tensor '0.weight': expected shape [4, 3], got [3, 4]");
}
TEST_CASE("data count disagrees with shape") {
  auto j = valid_doc();
  j["tensors"]["1.bias"] = {{"shape", {2}}, {"data", {1, 2, 3}}};
  CHECK(load_error(j).find("tensor '1.bias': data holds 3 values, shape [2] needs 2") != std::string::npos);
  j["tensors"]["1.bias"] = {{"shape", {2}}, {"dtype", "float32"}, {"data", b64(floats({1.f}))}};
  CHECK(load_error(j).find("tensor '1.bias': data holds 1 float32 values") != std::string::npos);
}
TEST_CASE("non-finite values are rejected") {
  auto j = valid_doc();
  j["tensors"]["1.bias"] = {{"shape", {2}}, {"dtype", "float32"},
                            {"data", b64(floats({1.f, std::numeric_limits<float>::quiet_NaN()}))}};
  CHECK(load_error(j) == "model.json: tensor '1.bias': non-finite value at flat index 1");
  j["tensors"]["1.bias"]["data"] = b64(floats({std::numeric_limits<float>::infinity(), 1.f}));
  CHECK(load_error(j).find("non-finite value at flat index 0") != std::string::npos);
}
TEST_CASE("bad base64, dtype and data types") {
  auto j = valid_doc();
  j["tensors"]["1.bias"] = {{"shape", {2}}, {"dtype", "float32"}, {"data", "@@@@"}};
  CHECK(load_error(j).find("'data' is not valid base64") != std::string::npos);
  j["tensors"]["1.bias"] = {{"shape", {2}}, {"dtype", "int8"}, {"data", "AAAA"}};
  CHECK(load_error(j).find("unknown dtype 'int8'") != std::string::npos);
  j["tensors"]["1.bias"] = {{"shape", {2}}, {"data", {1, "x"}}};
  CHECK(load_error(j).find("'data' holds a non-number (string)") != std::string::npos);
  j["tensors"]["1.bias"] = {{"shape", {-2}}, {"data", {1, 2}}};
  CHECK(load_error(j).find("'shape' must be an array of non-negative integers") != std::string::npos);
}
TEST_CASE("unknown version, unknown kind, wrong kind, wrong sizes") {
  auto j = valid_doc();
  j["version"] = 2;
  CHECK(load_error(j) == "model.json: unsupported version 2 (this library reads version 1)");
  j = valid_doc();
  j["kind"] = "transformer";
  CHECK(load_error(j).find("unknown model kind 'transformer' (known: mlp, ") != std::string::npos);
  CHECK(load_error(valid_doc(), "lobstr") == "model.json: model kind 'mlp' cannot be loaded as 'lobstr'");
  j = valid_doc();
  j["meta"]["input_size"] = 5;
  CHECK(load_error(j).find("do not match the network (3/2)") != std::string::npos);
  j = valid_doc();
  j["meta"].erase("output_size");
  CHECK(load_error(j) == "model.json: meta.output_size: expected a positive integer");
  j = valid_doc();
  j["format"] = "onnx";
  CHECK(load_error(j).find("'format' must be") != std::string::npos);
}
TEST_CASE("truncated and non-JSON files") {
  const std::string text = valid_doc().dump(2);
  const std::string e = load_error(text.substr(0, text.size() / 2));
  CHECK(e.rfind("model.json: not valid JSON", 0) == 0);
  CHECK(e.find("line") != std::string::npos);
  CHECK(load_error("").rfind("model.json: not valid JSON", 0) == 0);
  CHECK(load_error("\x89PNG\r\n").rfind("model.json: not valid JSON", 0) == 0);
  CHECK(load_error("[1, 2]") == "model.json: expected a JSON object at top level");
}
TEST_CASE("normalisation is validated") {
  auto j = valid_doc();
  j["normalization"]["input_mean"] = {{"shape", {3}}, {"data", {0, 0, 0}}};
  CHECK(load_error(j).find("normalization: 'input_mean' given without 'input_std'") != std::string::npos);
  j["normalization"]["input_std"] = {{"shape", {3}}, {"data", {1, 0, 1}}};
  CHECK(load_error(j).find("'input_std': value at index 1 must be > 0") != std::string::npos);
  j["normalization"]["input_std"] = {{"shape", {2}}, {"data", {1, 1}}};
  CHECK(load_error(j).find("tensor 'input_std': expected shape [3], got [2]") != std::string::npos);
  j["normalization"]["input_std"] = {{"shape", {3}}, {"data", {2, 2, 2}}};
  j["normalization"]["bogus"] = {{"shape", {3}}, {"data", {2, 2, 2}}};
  CHECK(load_error(j).find("unexpected tensor(s) 'bogus'") != std::string::npos);
}
TEST_CASE("missing file names the path") {
  try {
    nn::NetworkWeights<Net>::load("/nonexistent/dir/model.json", "mlp");
    FAIL("expected LoadError");
  } catch (const LoadError& e) {
    CHECK(std::string(e.what()) == "/nonexistent/dir/model.json: cannot open file (No such file or directory)");
  }
}
