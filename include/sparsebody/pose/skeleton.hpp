// A joint hierarchy: names, parents (parents before children), rest offsets in metres.
// The standard skeleton (the one the network was trained on) travels in the weights file as
// meta.skeleton = {"names": [...], "parents": [...], "offsets": [[x, y, z], ...]}.
#pragma once
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "sparsebody/core/error.hpp"

namespace sparsebody::pose {

struct Skeleton {
  std::vector<std::string> names;
  std::vector<int> parents;
  std::vector<Eigen::Vector3d> offsets;

  int size() const noexcept { return static_cast<int>(names.size()); }
  // Index of a joint by exact name, -1 when absent.
  int find(std::string_view name) const noexcept {
    for (int i = 0; i < size(); ++i)
      if (names[i] == name) return i;
    return -1;
  }
  // Index of the first child of j, -1 for a leaf.
  int first_child(int j) const noexcept {
    for (int i = j + 1; i < size(); ++i)
      if (parents[i] == j) return i;
    return -1;
  }

  // Reads meta.skeleton; `source` names the file in errors.
  static Skeleton from_json(const nlohmann::json& j, const std::string& source) {
    auto fail = [&](const std::string& what) { throw LoadError(source, "meta.skeleton: " + what); };
    if (!j.is_object() || !j.contains("names") || !j.contains("parents") || !j.contains("offsets"))
      fail("expected an object with 'names', 'parents' and 'offsets'");
    Skeleton s;
    const auto& n = j["names"];
    const auto& p = j["parents"];
    const auto& o = j["offsets"];
    if (!n.is_array() || !p.is_array() || !o.is_array() || n.size() != p.size() || n.size() != o.size() || n.empty())
      fail("'names', 'parents' and 'offsets' must be non-empty arrays of equal length");
    for (std::size_t i = 0; i < n.size(); ++i) {
      if (!n[i].is_string()) fail("names[" + std::to_string(i) + "]: expected a string");
      if (!p[i].is_number_integer() || p[i].get<int>() >= static_cast<int>(i) || p[i].get<int>() < -1 ||
          (i > 0 && p[i].get<int>() < 0))
        fail("parents[" + std::to_string(i) + "]: expected the index of an earlier joint (-1 for the root only)");
      if (!o[i].is_array() || o[i].size() != 3 || !o[i][0].is_number() || !o[i][1].is_number() || !o[i][2].is_number())
        fail("offsets[" + std::to_string(i) + "]: expected [x, y, z]");
      s.names.push_back(n[i].get<std::string>());
      s.parents.push_back(p[i].get<int>());
      s.offsets.emplace_back(o[i][0].get<double>(), o[i][1].get<double>(), o[i][2].get<double>());
    }
    if (s.parents[0] != -1) fail("parents[0]: the first joint must be the root (-1)");
    return s;
  }
};

}  // namespace sparsebody::pose
