// Maps a skeleton's joints to body roles by name, so skeletons from different sources (the
// training data's, CMU's, a user's rig) can be read, driven and compared.
// A name is matched after normalize_joint_name: the part after its last ':' (a namespace:
// "mixamorig:Hips"), lower case, alphanumerics only, without a rig's prefix ("Bip01 L Thigh",
// "CC_Base_L_Thigh", "J_Bip_L_Foot", "DEF-thigh.L"). Each role has candidate names, tried in order;
// a joint takes at most one role:
//   1. exact: the first candidate some joint's name equals;
//   2. for a role still without a joint, a name that ends with a candidate of 4 or more characters
//      ("Character1_LeftUpLeg", "Armature_Hips").
// Rigs this covers (tests/pipeline/rig_names.json): the training data's, CMU, Mixamo, LAFAN1,
// SMPL / AMASS (its L_Ankle is the foot, its L_Foot the toe, its L_Wrist the hand: wrists and
// ankles are tried first, and a toe role falls back to a foot name no other role took), Unreal's
// mannequin (thigh_l, calf_l, ball_l), 3ds Max Biped, Reallusion CC, VRM, Blender (thigh.L).
// Python twin: weights_tool/lobstr/skeleton.py ROLE_NAMES, RIG_PREFIXES, map_roles (keep them equal).
#pragma once
#include <array>
#include <cctype>
#include <cstring>
#include <initializer_list>
#include <string>
#include <vector>

#include "sparsebody/core/error.hpp"
#include "sparsebody/pose/skeleton.hpp"

namespace sparsebody::pose {

enum class Role : int { Hips, Spine, Head, HandL, HandR, UpLegL, UpLegR, LegL, LegR, FootL, FootR, ToeL, ToeR, Count };
inline constexpr int kRoleCount = static_cast<int>(Role::Count);

inline const char* role_name(Role r) noexcept {
  static const char* n[] = {"hips", "spine", "head", "hand_l", "hand_r", "upleg_l", "upleg_r",
                            "leg_l", "leg_r", "foot_l", "foot_r", "toe_l", "toe_r"};
  return n[static_cast<int>(r)];
}

inline std::string normalize_joint_name(const std::string& s) {
  const std::size_t colon = s.rfind(':');
  std::string o;
  for (std::size_t i = colon == std::string::npos ? 0 : colon + 1; i < s.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    if (std::isalnum(c)) o.push_back(static_cast<char>(std::tolower(c)));
  }
  // a rig's prefix (the longer of two that share a start comes first)
  for (const char* p : {"bip001", "bip01", "ccbase", "jbipc", "jbip", "def"}) {
    const std::size_t n = std::strlen(p);
    if (o.size() > n && o.compare(0, n, p) == 0) return o.substr(n);
  }
  return o;
}

struct JointMap {
  std::array<int, kRoleCount> joint{};  // role -> joint index (-1: absent; only Spine may be absent)
  int operator[](Role r) const noexcept { return joint[static_cast<int>(r)]; }

  // Throws LoadError(source, ...) naming the roles no joint matched.
  static JointMap from_names(const Skeleton& s, const std::string& source) {
    static const std::initializer_list<const char*> names[kRoleCount] = {
        {"hips", "pelvis", "hip"},
        {"spine", "lowerback", "spine1", "spine01", "abdomen", "waist"},
        {"head"},
        {"lwrist", "leftwrist", "wristl", "handl", "lefthand", "lhand"},
        {"rwrist", "rightwrist", "wristr", "handr", "righthand", "rhand"},
        {"upperlegl", "leftupleg", "lthigh", "leftthigh", "thighl", "leftupperleg", "lupperleg", "lhip", "lefthip"},
        {"upperlegr", "rightupleg", "rthigh", "rightthigh", "thighr", "rightupperleg", "rupperleg", "rhip", "righthip"},
        {"lowerlegl", "leftleg", "lshin", "leftshin", "shinl", "leftlowerleg", "llowerleg", "lcalf", "calfl", "lknee", "leftknee"},
        {"lowerlegr", "rightleg", "rshin", "rightshin", "shinr", "rightlowerleg", "rlowerleg", "rcalf", "calfr", "rknee", "rightknee"},
        {"lankle", "leftankle", "anklel", "footl", "leftfoot", "lfoot"},
        {"rankle", "rightankle", "ankler", "footr", "rightfoot", "rfoot"},
        {"toesl", "lefttoebase", "lefttoe", "ltoe", "ltoes", "lefttoes", "ltoebase", "toel", "ltoe0", "balll", "footl", "leftfoot", "lfoot"},
        {"toesr", "righttoebase", "righttoe", "rtoe", "rtoes", "righttoes", "rtoebase", "toer", "rtoe0", "ballr", "footr", "rightfoot", "rfoot"}};
    std::vector<std::string> norm(static_cast<std::size_t>(s.size()));
    for (int j = 0; j < s.size(); ++j) norm[static_cast<std::size_t>(j)] = normalize_joint_name(s.names[j]);
    std::vector<char> taken(norm.size(), 0);
    JointMap m;
    m.joint.fill(-1);
    auto ends_with = [](const std::string& a, const std::string& b) {
      return a.size() >= b.size() && a.compare(a.size() - b.size(), b.size(), b) == 0;
    };
    for (const bool suffix : {false, true})
      for (int r = 0; r < kRoleCount; ++r)
        for (const char* cand : names[r]) {
          if (m.joint[r] >= 0) break;
          const std::string c = cand;
          if (suffix && c.size() < 4) continue;
          for (std::size_t j = 0; j < norm.size() && m.joint[r] < 0; ++j)
            if (!taken[j] && (suffix ? ends_with(norm[j], c) : norm[j] == c)) {
              m.joint[r] = static_cast<int>(j);
              taken[j] = 1;
            }
        }
    std::string missing;
    for (int r = 0; r < kRoleCount; ++r)
      if (m.joint[r] < 0 && r != static_cast<int>(Role::Spine))
        missing += (missing.empty() ? "" : ", ") + std::string(role_name(static_cast<Role>(r)));
    if (!missing.empty()) throw LoadError(source, "cannot map joints by name: no joint for " + missing);
    return m;
  }
};

// Thigh + shin length (the height-scale measure shared with weights_tool/lobstr/skeleton.py).
inline double leg_length(const Skeleton& s, const JointMap& m) noexcept {
  return s.offsets[m[Role::LegL]].norm() + s.offsets[m[Role::FootL]].norm();
}

// Rest position of joint j relative to its ancestor `a` (sum of offsets along the chain).
inline Eigen::Vector3d rest_offset(const Skeleton& s, int j, int a) noexcept {
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  for (; j != a && j >= 0; j = s.parents[j]) v += s.offsets[j];
  return v;
}

// The joint that gives the pelvis its up axis: the lowest joint on the way from the hips to the
// head whose rest position is away from the hips (> 5 % of the leg; CMU's LowerBack sits on the hips).
inline int spine_base(const Skeleton& s, const JointMap& m) noexcept {
  int chain[64], n = 0;
  for (int j = m[Role::Head]; j != m[Role::Hips] && j >= 0 && n < 64; j = s.parents[j]) chain[n++] = j;
  const double min_len = 0.05 * leg_length(s, m);
  for (int i = n - 1; i >= 0; --i)
    if (rest_offset(s, chain[i], m[Role::Hips]).norm() > min_len) return chain[i];
  return n > 0 ? chain[0] : m[Role::Head];
}

// Orthonormal frame X = left (made orthogonal to up), Y = up, Z = X x Y = forward.
inline Eigen::Matrix3d left_up_frame(const Eigen::Vector3d& up, const Eigen::Vector3d& left) noexcept {
  const Eigen::Vector3d y = up.normalized();
  const Eigen::Vector3d x = (left - left.dot(y) * y).normalized();
  Eigen::Matrix3d F;
  F.col(0) = x;
  F.col(1) = y;
  F.col(2) = x.cross(y);
  return F;
}

// The pelvis tracker frame in hips-local coordinates (rest pose): Y = up (towards spine_base),
// X = left (left minus right thigh root), Z = forward. Python twin: skeleton.hips_local_frame.
inline Eigen::Matrix3d hips_tracker_frame(const Skeleton& s, const JointMap& m) noexcept {
  const int h = m[Role::Hips];
  return left_up_frame(rest_offset(s, spine_base(s, m), h),
                       rest_offset(s, m[Role::UpLegL], h) - rest_offset(s, m[Role::UpLegR], h));
}

// The standard skeleton's hips joint (the training data's, Bandai Namco's) sits on the pelvis's up
// axis 0.0274 leg lengths above the midpoint of the thigh roots (2.19 cm on its 80.07 cm thigh +
// shin), neither forward nor back. Rigs differ: CMU's root "Hips" is 10.8 cm above that midpoint and
// 3.9 cm behind it, at the lower back. Python twin: skeleton.STANDARD_HIPS_ABOVE_THIGH_ROOTS.
inline constexpr double kStandardHipsAboveThighRoots = 2.19248 / (39.0811 + 40.9854);

// Where the standard skeleton's hips joint lies on this rig, in hips-local rest coordinates (the
// rig's units): the midpoint of the thigh roots plus kStandardHipsAboveThighRoots leg lengths along
// the pelvis's up axis (hips_tracker_frame). Zero where that is within 0.6 % of the leg (5 mm) of the
// rig's own hips joint (every training clip: their trackers stay bit for bit), so that a pelvis
// tracker synthesised "at the hips" of another rig sits where the avatar's hips joint belongs, and
// its torso is measured from there. Python twin: skeleton.standard_hips_point.
inline Eigen::Vector3d standard_hips_point(const Skeleton& s, const JointMap& m) noexcept {
  const int h = m[Role::Hips];
  const double leg = leg_length(s, m);
  const Eigen::Vector3d mid = 0.5 * (rest_offset(s, m[Role::UpLegL], h) + rest_offset(s, m[Role::UpLegR], h));
  const Eigen::Vector3d p = mid + hips_tracker_frame(s, m).col(1) * (kStandardHipsAboveThighRoots * leg);
  return !(p.norm() >= 0.006 * leg) || !p.allFinite() ? Eigen::Vector3d::Zero() : p;
}

}  // namespace sparsebody::pose
