// Maps a skeleton's joints to body roles by name, so skeletons from different sources (the
// training data's, CMU's, a user's rig) can be read, driven and compared. Names are matched after
// lower-casing and dropping non-alphanumerics ("Hand_L", "LeftHand", "l_wrist" ...).
// Python twin: weights_tool/lobstr/skeleton.py ROLE_NAMES (keep the lists equal).
#pragma once
#include <array>
#include <cctype>
#include <initializer_list>
#include <string>

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
  std::string o;
  for (char c : s)
    if (std::isalnum(static_cast<unsigned char>(c))) o.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
  return o;
}

struct JointMap {
  std::array<int, kRoleCount> joint{};  // role -> joint index (-1: absent; only Spine may be absent)
  int operator[](Role r) const noexcept { return joint[static_cast<int>(r)]; }

  // Throws LoadError(source, ...) naming the roles no joint matched.
  static JointMap from_names(const Skeleton& s, const std::string& source) {
    static const std::initializer_list<const char*> names[kRoleCount] = {
        {"hips", "pelvis", "hip"},
        {"spine", "lowerback", "spine1", "abdomen", "waist"},
        {"head"},
        {"handl", "lefthand", "lhand", "lwrist", "leftwrist"},
        {"handr", "righthand", "rhand", "rwrist", "rightwrist"},
        {"upperlegl", "leftupleg", "lthigh", "leftthigh", "leftupperleg", "lhip", "lefthip"},
        {"upperlegr", "rightupleg", "rthigh", "rightthigh", "rightupperleg", "rhip", "righthip"},
        {"lowerlegl", "leftleg", "lshin", "leftshin", "leftlowerleg", "lknee", "leftknee"},
        {"lowerlegr", "rightleg", "rshin", "rightshin", "rightlowerleg", "rknee", "rightknee"},
        {"footl", "leftfoot", "lfoot", "lankle", "leftankle"},
        {"footr", "rightfoot", "rfoot", "rankle", "rightankle"},
        {"toesl", "lefttoebase", "lefttoe", "ltoe", "ltoes", "lefttoes"},
        {"toesr", "righttoebase", "righttoe", "rtoe", "rtoes", "righttoes"}};
    JointMap m;
    std::string missing;
    for (int r = 0; r < kRoleCount; ++r) {
      m.joint[r] = -1;
      for (const char* cand : names[r]) {
        for (int j = 0; j < s.size() && m.joint[r] < 0; ++j)
          if (normalize_joint_name(s.names[j]) == cand) m.joint[r] = j;
        if (m.joint[r] >= 0) break;
      }
      if (m.joint[r] < 0 && r != static_cast<int>(Role::Spine))
        missing += (missing.empty() ? "" : ", ") + std::string(role_name(static_cast<Role>(r)));
    }
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

}  // namespace sparsebody::pose
