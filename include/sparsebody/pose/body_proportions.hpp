// A user's proportions relative to the standard skeleton, and the standard skeleton re-proportioned
// to them (issue 12, "any body"). The pipelines work in the standard skeleton's scale (the height
// scale s maps the user's standing eye height to the standard one, features/calibration.hpp); what
// the height scale cannot show is how that height splits between legs and torso, and how long the
// arms are. Three ratios, each multiplying a group of segments (the grouping of weights_tool/
// devices.py and bodies.py, which make the training and test bodies):
//   leg    thigh, shin, foot (the knee, ankle and toe offsets);
//   torso  the spine chain from the hips to the head, the clavicles and shoulder joints, the hip
//          joints' offsets from the pelvis;
//   arm    upper arm and forearm (the elbow and wrist offsets).
// The head stays where it is: a leg ratio r gives the torso ratio that keeps the standing head
// height, t = (H_head - r H_hips) / (H_head - H_hips) (torso_for_legs).
// Works on any skeleton with the roles of pose/joint_map.hpp; no allocation (offsets are written
// into a skeleton of the same size).
#pragma once
#include <algorithm>
#include <cmath>

#include "sparsebody/pose/joint_map.hpp"
#include "sparsebody/pose/skeleton.hpp"

namespace sparsebody::pose {

struct BodyProportions {
  double leg = 1.0, torso = 1.0, arm = 1.0;

  bool standard() const noexcept { return leg == 1.0 && torso == 1.0 && arm == 1.0; }

  // Each ratio held within [0.75, 1.33]; a non-finite one is 1 (what an application's explicit
  // proportions go through).
  BodyProportions sane() const noexcept {
    auto f = [](double r) { return std::isfinite(r) ? std::clamp(r, 0.75, 1.33) : 1.0; };
    return {f(leg), f(torso), f(arm)};
  }

  // The torso ratio that keeps the standing head height H_head for legs r times the standard
  // (standing hips height H_hips).
  static double torso_for_legs(double r, double standing_hips, double standing_head) noexcept {
    const double span = standing_head - standing_hips;
    return span > 1e-6 ? (standing_head - r * standing_hips) / span : 1.0;
  }
};

// out.offsets = standard's, each group multiplied by its ratio. `out` must have standard's joints
// (a copy made at construction); only offsets are written.
inline void apply_proportions(const Skeleton& standard, const JointMap& m, const BodyProportions& p, Skeleton& out) noexcept {
  const int n = std::min(standard.size(), out.size());
  for (int j = 0; j < n; ++j) out.offsets[j] = standard.offsets[j];
  auto scale = [&](int j, double k) {
    if (j > 0 && j < n) out.offsets[j] = standard.offsets[j] * k;
  };
  for (const Role r : {Role::LegL, Role::LegR, Role::FootL, Role::FootR, Role::ToeL, Role::ToeR}) scale(m[r], p.leg);
  // the spine chain, head down to (not including) the hips
  for (int j = m[Role::Head]; j > 0 && j != m[Role::Hips]; j = standard.parents[j]) scale(j, p.torso);
  scale(m[Role::UpLegL], p.torso);
  scale(m[Role::UpLegR], p.torso);
  for (const Role h : {Role::HandL, Role::HandR}) {
    const int hand = m[h];
    if (hand <= 0) continue;
    const int lower = standard.parents[hand];                      // forearm's root (elbow)
    const int upper = lower > 0 ? standard.parents[lower] : -1;    // upper arm's root (shoulder)
    scale(hand, p.arm);
    scale(lower, p.arm);
    // shoulder joint and clavicle: up to the spine chain, part of the torso
    for (int j = upper, k = 0; j > 0 && k < 2; j = standard.parents[j], ++k) {
      bool on_spine = false;
      for (int s = m[Role::Head]; s > 0; s = standard.parents[s]) on_spine |= s == j;
      if (on_spine) break;
      scale(j, p.torso);
    }
  }
}

// Upper arm + forearm of the arm that ends at `hand` (its own and its parent's offsets); 0 when
// `hand` is not a joint below an elbow.
inline double arm_length(const Skeleton& s, int hand) noexcept {
  const int lower = hand > 0 && hand < s.size() ? s.parents[hand] : -1;  // the forearm's root (elbow)
  return lower > 0 ? s.offsets[hand].norm() + s.offsets[lower].norm() : 0.0;
}

// The segment-group lengths the ratios compare (any units): leg = thigh + shin (leg_length), torso
// = the rest distance from the hips joint (where the standard skeleton has it: standard_hips_point)
// to the head, arm = upper arm + forearm (left side).
struct BodyLengths {
  double leg = 0, torso = 0, arm = 0;
  static BodyLengths of(const Skeleton& s, const JointMap& m) noexcept {
    BodyLengths b;
    b.leg = leg_length(s, m);
    b.torso = (rest_offset(s, m[Role::Head], m[Role::Hips]) - standard_hips_point(s, m)).norm();
    b.arm = arm_length(s, m[Role::HandL]);
    return b;
  }
};

// The proportions of a body whose lengths are `user` (any units), sized to the standard skeleton by
// leg length (as trackers at the joints of a mocap clip are: the demo's BVH input): leg 1, torso and
// arm the user's over the standard's after that scaling, each held within [0.75, 1.33] (a length
// that does not map is 1).
inline BodyProportions proportions_by_leg(const BodyLengths& user, const BodyLengths& standard) noexcept {
  BodyProportions p;
  if (!(user.leg > 0) || !(standard.leg > 0)) return p;
  const double k = standard.leg / user.leg;
  auto ratio = [&](double u, double s) { return u > 0 && s > 0 && std::isfinite(u) ? std::clamp(k * u / s, 0.75, 1.33) : 1.0; };
  p.torso = ratio(user.torso, standard.torso);
  p.arm = ratio(user.arm, standard.arm);
  return p;
}

}  // namespace sparsebody::pose
