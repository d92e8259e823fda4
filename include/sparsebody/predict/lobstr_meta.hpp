// What a LoBSTr weights file's meta says (weights_tool/lobstr/export.py), parsed once at load: the
// standard skeleton, the 8 predicted lower-body joints, rates and standing heights.
#pragma once
#include <string>

#include "sparsebody/core/error.hpp"
#include "sparsebody/io/weights_json.hpp"
#include "sparsebody/pose/skeleton.hpp"

namespace sparsebody::predict {

// What the weights file's meta says about the pipeline (see weights_tool/lobstr/export.py).
struct LoBSTrMeta {
  pose::Skeleton skeleton;      // standard skeleton, metres
  int lower[8] = {};            // joint indices of the 8 predicted joints
  double frame_rate = 30;
  double standing_hips_height = 0.9, standing_head_height = 1.38;
  double toe_height = 0.042;    // standing height of the toe-base joint above the floor

  // A meta value of the wrong JSON type (a string where a number belongs) is a LoadError too.
  static LoBSTrMeta from(const io::ModelInfo& info) {
    try {
      return parse(info);
    } catch (const nlohmann::json::exception& e) {
      throw LoadError(info.source, std::string("meta: unexpected value: ") + excerpt(e.what(), 200));
    }
  }

 private:
  static LoBSTrMeta parse(const io::ModelInfo& info) {
    const std::string& src = info.source;
    LoBSTrMeta m;
    const auto& j = info.meta;
    if (!j.contains("skeleton")) throw LoadError(src, "meta.skeleton: missing (not a LoBSTr pipeline file)");
    m.skeleton = pose::Skeleton::from_json(j["skeleton"], src);
    if (!j.contains("lower_body_joints") || !j["lower_body_joints"].is_array() || j["lower_body_joints"].size() != 8)
      throw LoadError(src, "meta.lower_body_joints: expected 8 joint names");
    for (int i = 0; i < 8; ++i) {
      const auto& n = j["lower_body_joints"][i];
      m.lower[i] = n.is_string() ? m.skeleton.find(n.get<std::string>()) : -1;
      if (m.lower[i] < 0) throw LoadError(src, "meta.lower_body_joints[" + std::to_string(i) + "]: not a skeleton joint");
    }
    if (info.frame_rate > 0) m.frame_rate = info.frame_rate;
    if (info.rotation_representation != "6d" || info.rotation_layout != "columns" ||
        j["rotation"].value("columns", nlohmann::json::array()) != nlohmann::json::array({2, 1}))
      throw LoadError(src, "meta.rotation: expected {\"representation\": \"6d\", \"layout\": \"columns\", \"columns\": [2, 1]}");
    m.standing_hips_height = j.value("standing_hips_height", m.standing_hips_height);
    m.standing_head_height = j.value("standing_head_height", m.standing_head_height);
    m.toe_height = j.value("toe_height", m.toe_height);
    return m;
  }
};

}  // namespace sparsebody::predict
