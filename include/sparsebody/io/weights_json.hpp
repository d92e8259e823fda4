// Reader of the sparsebody weights format (JSON, version 1), documented in weights_tool/FORMAT.md.
//
//   {
//     "format": "sparsebody-weights", "version": 1, "kind": "lobstr",
//     "meta": { "input_size": 37, "output_size": 52, "frame_rate": 30,
//               "rotation": {"representation": "6d", "layout": "columns"}, "credit": "...", ... },
//     "normalization": { "input_mean": <tensor>, "input_std": <tensor>, ... },   (optional)
//     "tensors": { "gru.weight_ih_l0": <tensor>, ... }                           (state_dict names)
//   }
//   <tensor> = {"shape": [3072, 37], "dtype": "float32", "data": "<base64 little-endian>"}
//            | {"shape": [3072, 37], "data": [numbers, flat or nested]}
//
// Everything is checked; any problem is a LoadError naming the file and the field or tensor.
#pragma once
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "sparsebody/core/error.hpp"
#include "sparsebody/io/base64.hpp"
#include "sparsebody/io/tensor_table.hpp"

namespace sparsebody::io {

inline constexpr const char* kWeightsFormat = "sparsebody-weights";
inline constexpr int kWeightsVersion = 1;

// Model kinds this version of the library knows; each network type declares the one it loads.
inline const std::vector<std::string>& known_model_kinds() {
  static const std::vector<std::string> kinds = {"mlp",        "gru",       "sequential",
                                                 "lobstr",     "n3p_signal", "n3p_lower",
                                                 "n3p_upper",  "n3p_policy", "n3p_correction_policy", "questsim_policy"};
  return kinds;
}

// Everything in a weights file except the network tensors.
struct ModelInfo {
  std::string source;  // file name (or label) for messages
  std::string kind;
  int version = 0;
  int input_size = 0;
  int output_size = 0;
  double frame_rate = 0;            // 0 when the file does not say
  std::string rotation_representation;  // e.g. "6d", "quaternion"; empty when not said
  std::string rotation_layout;          // for 6d: "columns" (first two columns) or "rows"
  std::string credit, license;
  nlohmann::json meta;  // the whole "meta" object, for pipeline-specific fields
  TensorTable normalization;
};

struct WeightsDocument {
  ModelInfo info;
  TensorTable tensors;
};

namespace detail {

inline std::vector<std::int64_t> parse_shape(const nlohmann::json& j, const std::string& src, const std::string& what) {
  if (!j.is_array()) throw LoadError(src, what + ": 'shape' must be an array of non-negative integers");
  std::vector<std::int64_t> s;
  for (const auto& d : j) {
    if (!d.is_number_integer() || d.get<std::int64_t>() < 0)
      throw LoadError(src, what + ": 'shape' must be an array of non-negative integers");
    s.push_back(d.get<std::int64_t>());
  }
  return s;
}

inline void flatten_numbers(const nlohmann::json& j, std::vector<double>& out, const std::string& src, const std::string& what,
                            int depth = 0) {
  if (j.is_array()) {
    if (depth >= 16) throw LoadError(src, what + ": 'data' nests arrays deeper than 16 levels");
    for (const auto& e : j) flatten_numbers(e, out, src, what, depth + 1);
  } else if (j.is_number()) {
    out.push_back(j.get<double>());
  } else {
    throw LoadError(src, what + ": 'data' holds a non-number (" + std::string(j.type_name()) + ")");
  }
}

inline Tensor parse_tensor(const nlohmann::json& j, const std::string& src, const std::string& name) {
  const std::string what = "tensor '" + name + "'";
  if (!j.is_object()) throw LoadError(src, what + ": expected an object with 'shape' and 'data'");
  if (!j.contains("shape")) throw LoadError(src, what + ": missing 'shape'");
  if (!j.contains("data")) throw LoadError(src, what + ": missing 'data'");
  Tensor t;
  t.shape = parse_shape(j["shape"], src, what);
  // The element count, refused before anything is allocated when the data present cannot hold it
  // (a shape of [1e9, 1e9] next to a short string), and never allowed to overflow.
  const auto& data = j["data"];
  // A base64 string of n characters holds fewer than n values; number arrays are bounded by the
  // text itself and are only checked for overflow here.
  const std::size_t limit = data.is_string() ? data.get_ref<const std::string&>().size() : std::size_t(-1) / 16;
  std::size_t count = 1;
  for (auto d : t.shape) {
    if (d != 0 && count > limit / static_cast<std::size_t>(d))
      throw LoadError(src, what + ": shape " + shape_string(t.shape) + " is larger than its data");
    count *= static_cast<std::size_t>(d);
  }
  if (data.is_string()) {
    const std::string dtype = j.value("dtype", std::string("float32"));
    std::size_t width = dtype == "float32" ? 4 : dtype == "float64" ? 8 : 0;
    if (!width) throw LoadError(src, what + ": unknown dtype '" + dtype + "' (expected float32 or float64)");
    std::vector<std::uint8_t> bytes;
    if (!base64_decode(data.get_ref<const std::string&>(), bytes))
      throw LoadError(src, what + ": 'data' is not valid base64");
    if (bytes.size() != count * width)
      throw LoadError(src, what + ": data holds " + std::to_string(bytes.size() / width) + " " + dtype +
                               " values, shape " + shape_string(t.shape) + " needs " + std::to_string(count));
    t.values.resize(count);
    // The format is little-endian; so is every platform this library targets (x86-64, AArch64).
    if (width == 4) {
      for (std::size_t i = 0; i < count; ++i) {
        float f;
        std::memcpy(&f, bytes.data() + 4 * i, 4);
        t.values[i] = f;
      }
    } else {
      std::memcpy(t.values.data(), bytes.data(), count * 8);
    }
  } else if (data.is_array()) {
    flatten_numbers(data, t.values, src, what);
    if (t.values.size() != count)
      throw LoadError(src, what + ": data holds " + std::to_string(t.values.size()) + " values, shape " +
                               shape_string(t.shape) + " needs " + std::to_string(count));
  } else {
    throw LoadError(src, what + ": 'data' must be a base64 string or an array of numbers");
  }
  for (std::size_t i = 0; i < t.values.size(); ++i)
    if (!std::isfinite(t.values[i]))
      throw LoadError(src, what + ": non-finite value at flat index " + std::to_string(i));
  return t;
}

inline void parse_tensor_object(const nlohmann::json& j, TensorTable& table, const std::string& src, const std::string& field) {
  if (!j.is_object()) throw LoadError(src, "'" + field + "' must be an object of named tensors");
  for (auto it = j.begin(); it != j.end(); ++it)
    table.tensors().emplace(it.key(), parse_tensor(it.value(), src, it.key()));
}

inline int required_size(const nlohmann::json& meta, const char* key, const std::string& src) {
  if (!meta.contains(key) || !meta[key].is_number_integer() || meta[key].get<long long>() <= 0)
    throw LoadError(src, std::string("meta.") + key + ": expected a positive integer");
  return meta[key].get<int>();
}

}  // namespace detail

namespace detail {
// The checked document of a parsed JSON value (parse_weights below).
inline WeightsDocument document_of(const nlohmann::json& j, const std::string& source) {
  if (!j.is_object()) throw LoadError(source, "expected a JSON object at top level");
  if (j.value("format", std::string()) != kWeightsFormat)
    throw LoadError(source, std::string("'format' must be \"") + kWeightsFormat + "\"");
  if (!j.contains("version") || !j["version"].is_number_integer())
    throw LoadError(source, "missing integer 'version'");
  WeightsDocument doc{ModelInfo{}, TensorTable(source)};
  ModelInfo& info = doc.info;
  info.source = source;
  info.version = j["version"].get<int>();
  if (info.version != kWeightsVersion)
    throw LoadError(source, "unsupported version " + std::to_string(info.version) + " (this library reads version " +
                                std::to_string(kWeightsVersion) + ")");
  if (!j.contains("kind") || !j["kind"].is_string()) throw LoadError(source, "missing string 'kind'");
  info.kind = j["kind"].get<std::string>();
  bool known = false;
  std::string all;
  for (const auto& k : known_model_kinds()) {
    known |= k == info.kind;
    all += (all.empty() ? "" : ", ") + k;
  }
  if (!known) throw LoadError(source, "unknown model kind '" + info.kind + "' (known: " + all + ")");
  if (!j.contains("meta") || !j["meta"].is_object()) throw LoadError(source, "missing object 'meta'");
  info.meta = j["meta"];
  info.input_size = detail::required_size(info.meta, "input_size", source);
  info.output_size = detail::required_size(info.meta, "output_size", source);
  if (info.meta.contains("frame_rate")) {
    if (!info.meta["frame_rate"].is_number() || !(info.meta["frame_rate"].get<double>() > 0))
      throw LoadError(source, "meta.frame_rate: expected a positive number");
    info.frame_rate = info.meta["frame_rate"].get<double>();
  }
  if (info.meta.contains("rotation")) {
    const auto& r = info.meta["rotation"];
    if (!r.is_object() || !r.value("representation", nlohmann::json()).is_string())
      throw LoadError(source, "meta.rotation: expected {\"representation\": ..., \"layout\": ...}");
    info.rotation_representation = r["representation"].get<std::string>();
    info.rotation_layout = r.value("layout", std::string());
    if (info.rotation_representation == "6d" && info.rotation_layout != "columns" && info.rotation_layout != "rows")
      throw LoadError(source, "meta.rotation.layout: 6d rotations need \"columns\" or \"rows\"");
  }
  info.credit = info.meta.value("credit", std::string());
  info.license = info.meta.value("license", std::string());
  info.normalization = TensorTable(source);
  if (j.contains("normalization")) detail::parse_tensor_object(j["normalization"], info.normalization, source, "normalization");
  if (!j.contains("tensors")) throw LoadError(source, "missing object 'tensors'");
  detail::parse_tensor_object(j["tensors"], doc.tensors, source, "tensors");
  return doc;
}
}  // namespace detail

// Parses a weights document from text. `source` names it in error messages (usually the file path).
inline WeightsDocument parse_weights(const std::string& text, const std::string& source) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    // e.what() gives "... parse error at line L, column C: ..." (truncated files end here too).
    // e.what() ends with the last token read, which for a truncated tensor is all its base64:
    // LoadError keeps the message to one bounded line.
    throw LoadError(source, std::string("not valid JSON (truncated or corrupt?) at byte ") + std::to_string(e.byte) + ": " +
                                excerpt(e.what(), 200));
  } catch (const nlohmann::json::exception& e) {  // e.g. a number too large for a double (out_of_range.406)
    throw LoadError(source, std::string("not valid JSON: ") + excerpt(e.what(), 200));
  }
  // Any JSON value of an unexpected type below (an object where a string belongs) is a LoadError too.
  try {
    return detail::document_of(j, source);
  } catch (const nlohmann::json::exception& e) {
    throw LoadError(source, std::string("unexpected JSON value: ") + excerpt(e.what(), 200));
  }
}

inline std::string read_text_file(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw LoadError::cannot_open(path);
  std::ostringstream ss;
  ss << f.rdbuf();
  if (f.bad()) throw LoadError(path, "read error");
  return ss.str();
}

inline WeightsDocument read_weights_file(const std::string& path) { return parse_weights(read_text_file(path), path); }

}  // namespace sparsebody::io
