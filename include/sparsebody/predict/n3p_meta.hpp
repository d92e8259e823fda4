// What the Neural3Points weights files' meta says (weights_tool/n3p/export.py), parsed once at
// load: the standard skeleton, the joint sets J_lo / J_up, the default standing state.
#pragma once
#include <array>
#include <string>

#include "sparsebody/core/error.hpp"
#include "sparsebody/features/n3p_state.hpp"
#include "sparsebody/io/weights_json.hpp"
#include "sparsebody/pose/skeleton.hpp"

namespace sparsebody::predict {

namespace n3p = features::n3p;

// What the weights files' meta says (weights_tool/n3p/export.py): skeleton, joint sets, default state.
struct N3PMeta {
  pose::Skeleton skeleton;
  std::array<int, n3p::kLowerJoints> lower{};  // skeleton index of J_lo[i]
  std::array<int, n3p::kUpperJoints> upper{};  // skeleton index of J_up[i]
  std::array<double, n3p::kGlo> glo0{};        // g_lo^0
  std::array<double, n3p::kGup> gup0{};        // g_up^0
  std::array<double, n3p::kO> o0{};            // o*^0 (in h^0)
  double frame_rate = 30;
  double standing_hips_height = 0.908, standing_head_height = 1.378;

  // A meta value of the wrong JSON type (a string where a number belongs) is a LoadError too.
  static N3PMeta from(const io::ModelInfo& info) {
    try {
      return parse(info);
    } catch (const nlohmann::json::exception& e) {
      throw LoadError(info.source, std::string("meta: unexpected value: ") + excerpt(e.what(), 200));
    }
  }

 private:
  static N3PMeta parse(const io::ModelInfo& info) {
    const std::string& src = info.source;
    const auto& j = info.meta;
    N3PMeta m;
    if (!j.contains("skeleton")) throw LoadError(src, "meta.skeleton: missing (not a Neural3Points file)");
    m.skeleton = pose::Skeleton::from_json(j["skeleton"], src);
    auto joints = [&](const char* key, const char* const* names, int n, int* out) {
      if (!j.contains(key) || !j[key].is_array() || static_cast<int>(j[key].size()) != n)
        throw LoadError(src, std::string("meta.") + key + ": expected " + std::to_string(n) + " joint names");
      for (int i = 0; i < n; ++i) {
        const auto& e = j[key][i];
        if (!e.is_string() || e.get<std::string>() != names[i])
          throw LoadError(src, std::string("meta.") + key + "[" + std::to_string(i) + "]: expected " + names[i]);
        out[i] = m.skeleton.find(names[i]);
        if (out[i] < 0) throw LoadError(src, std::string("meta.") + key + ": " + names[i] + " is not a skeleton joint");
      }
    };
    joints("lower_body_joints", n3p::kLowerNames, n3p::kLowerJoints, m.lower.data());
    joints("upper_body_joints", n3p::kUpperNames, n3p::kUpperJoints, m.upper.data());
    if (info.rotation_representation != "6d" || info.rotation_layout != "columns" ||
        j["rotation"].value("columns", nlohmann::json::array()) != nlohmann::json::array({2, 1}))
      throw LoadError(src, "meta.rotation: expected {\"representation\": \"6d\", \"layout\": \"columns\", \"columns\": [2, 1]}");
    if (!j.contains("initial_state") || !j["initial_state"].is_object())
      throw LoadError(src, "meta.initial_state: missing");
    const auto& s = j["initial_state"];
    auto vec = [&](const char* key, double* out, int n) {
      if (!s.contains(key) || !s[key].is_array() || static_cast<int>(s[key].size()) != n)
        throw LoadError(src, std::string("meta.initial_state.") + key + ": expected " + std::to_string(n) + " numbers");
      for (int i = 0; i < n; ++i) {
        if (!s[key][i].is_number()) throw LoadError(src, std::string("meta.initial_state.") + key + ": not a number");
        out[i] = s[key][i].get<double>();
        if (!std::isfinite(out[i])) throw LoadError(src, std::string("meta.initial_state.") + key + ": not finite");
      }
    };
    vec("g_lo", m.glo0.data(), n3p::kGlo);
    vec("g_up", m.gup0.data(), n3p::kGup);
    vec("o", m.o0.data(), n3p::kO);
    if (info.frame_rate > 0) m.frame_rate = info.frame_rate;
    m.standing_hips_height = j.value("standing_hips_height", m.standing_hips_height);
    m.standing_head_height = j.value("standing_head_height", m.standing_head_height);
    return m;
  }
};

}  // namespace sparsebody::predict
