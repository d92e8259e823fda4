// Joint roles by name on the rigs users bring (tests/pipeline/rig_names.json, shared with the Python
// twin's test in weights_tool/tests/test_lobstr_pipeline.py): each role on the joint the rig means,
// a rig without toes refused with the roles it lacks.
#include <doctest/doctest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "sparsebody/core/error.hpp"
#include "sparsebody/pose/joint_map.hpp"

using namespace sparsebody;

namespace {

nlohmann::json rigs() {
  std::ifstream f(SPARSEBODY_SOURCE_DIR "/tests/pipeline/rig_names.json");
  REQUIRE(f.good());
  return nlohmann::json::parse(f);
}

pose::Skeleton named(const nlohmann::json& names) {
  pose::Skeleton s;
  for (const auto& n : names) {
    s.names.push_back(n.get<std::string>());
    s.parents.push_back(static_cast<int>(s.parents.size()) - 1);  // only the names are matched
    s.offsets.push_back(Eigen::Vector3d::Zero());
  }
  return s;
}

}  // namespace

TEST_CASE("joint roles by name: every role on the joint each common rig means") {
  const nlohmann::json d = rigs();
  REQUIRE(d["rigs"].size() >= 12);
  for (const auto& r : d["rigs"]) {
    CAPTURE(r["rig"].get<std::string>());
    const pose::Skeleton s = named(r["names"]);
    const pose::JointMap m = pose::JointMap::from_names(s, r["rig"].get<std::string>());
    for (int k = 0; k < pose::kRoleCount; ++k) {
      const pose::Role role = static_cast<pose::Role>(k);
      CAPTURE(pose::role_name(role));
      const auto& want = r["roles"][pose::role_name(role)];
      if (want.is_null())
        CHECK(m[role] == -1);
      else
        CHECK((m[role] >= 0 ? s.names[m[role]] : std::string("(none)")) == want.get<std::string>());
    }
  }
}

TEST_CASE("joint roles by name: names are normalized (namespace, case, separators, a rig's prefix); a rig without toes is refused") {
  CHECK(pose::normalize_joint_name("mixamorig:LeftUpLeg") == "leftupleg");
  CHECK(pose::normalize_joint_name("Bip01 L Thigh") == "lthigh");
  CHECK(pose::normalize_joint_name("CC_Base_L_Calf") == "lcalf");
  CHECK(pose::normalize_joint_name("J_Bip_C_Hips") == "hips");
  CHECK(pose::normalize_joint_name("DEF-thigh.L") == "thighl");
  CHECK(pose::normalize_joint_name("Bip01") == "bip01");  // a prefix alone is a name
  for (const auto& r : rigs()["unmappable"]) {
    std::string expected = "no joint for ";
    for (const auto& role : r["missing"]) expected += (expected.back() == ' ' ? "" : ", ") + role.get<std::string>();
    try {
      pose::JointMap::from_names(named(r["names"]), "rig.bvh");
      FAIL("no error for a rig without " << expected);
    } catch (const LoadError& e) {
      const std::string what = e.what();
      CHECK(what.find("rig.bvh") != std::string::npos);
      CHECK(what.find(expected) != std::string::npos);
    }
  }
}
