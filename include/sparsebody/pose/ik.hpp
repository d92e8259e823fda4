// Inverse kinematics used by the pipelines: aim frames, the analytic two-bone solver, and
// limb_to, the one "limb to target" solve of a 3-joint chain (positions and the bones' world
// rotations) that every pipeline's arm and leg IK uses. Positions in metres; rotations are world
// rotations unless said otherwise.
#pragma once
#include <algorithm>
#include <cmath>
#include <type_traits>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "sparsebody/pose/body_pose.hpp"

namespace sparsebody::pose {

// Orthonormal frame whose first axis is a and whose second lies in the (a, b) plane.
inline Eigen::Matrix3d frame_from(const Eigen::Vector3d& a, const Eigen::Vector3d& b) noexcept {
  const Eigen::Vector3d x = a.normalized();
  Eigen::Vector3d y = b - b.dot(x) * x;
  if (y.norm() < 1e-9) {  // b parallel to a: any perpendicular
    y = std::abs(x.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    y -= y.dot(x) * x;
  }
  y.normalize();
  Eigen::Matrix3d F;
  F.col(0) = x;
  F.col(1) = y;
  F.col(2) = x.cross(y);
  return F;
}

// World rotation R that maps the joint-local axis `a_local` onto `a_world` exactly and brings
// `b_local` as close as possible to `b_world` (an "aim" constraint with an up/twist vector).
inline Eigen::Quaterniond aim(const Eigen::Vector3d& a_local, const Eigen::Vector3d& b_local,
                              const Eigen::Vector3d& a_world, const Eigen::Vector3d& b_world) noexcept {
  return Eigen::Quaterniond(frame_from(a_world, b_world) * frame_from(a_local, b_local).transpose());
}

// Two-bone IK on positions: a (root, fixed), b (middle), c (end) with bone lengths |b - a| and
// |c - b| kept; the end goes to `target` (clamped to the reachable shell) and the middle bends
// towards `pole` (the current bend is used when the pole is along the reach line).
// Law of cosines: cos(alpha) = (l1^2 + d^2 - l2^2) / (2 l1 d), alpha at a between reach and bone 1.
inline void two_bone(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                     const Eigen::Vector3d& target, const Eigen::Vector3d& pole, Eigen::Vector3d& b_out,
                     Eigen::Vector3d& c_out) noexcept {
  const double l1 = (b - a).norm(), l2 = (c - b).norm();
  Eigen::Vector3d reach = target - a;
  double d = reach.norm();
  const Eigen::Vector3d dir = d > 1e-9 ? Eigen::Vector3d(reach / d) : Eigen::Vector3d((c - a).normalized());
  d = std::clamp(d, std::abs(l1 - l2) + 1e-6, l1 + l2 - 1e-6);
  Eigen::Vector3d n = pole - pole.dot(dir) * dir;
  if (n.norm() < 1e-6) n = (b - a) - (b - a).dot(dir) * dir;
  if (n.norm() < 1e-9) n = std::abs(dir.y()) < 0.9 ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitZ(), n -= n.dot(dir) * dir;
  n.normalize();
  const double ca = std::clamp((l1 * l1 + d * d - l2 * l2) / (2 * l1 * d), -1.0, 1.0);
  b_out = a + l1 * (ca * dir + std::sqrt(std::max(0.0, 1 - ca * ca)) * n);
  c_out = a + d * dir;
}

// Shortest rotation taking direction u to direction v.
inline Eigen::Quaterniond swing(const Eigen::Vector3d& u, const Eigen::Vector3d& v) noexcept {
  return Eigen::Quaterniond::FromTwoVectors(u, v);
}

// How limb_to finds the two bones' new world rotations W_a', W_b' (a: the chain's root joint, b
// its middle joint; s_a = swing(b - a, b' - a) turns the upper bone onto its new direction).
//   Composed    s_b = swing(s_a (c - b), c' - b'),               W_a' = s_a W_a, W_b' = (s_b s_a) W_b
//               (Neural3Points: direct mode, control predictor);
//   Sequential  c~ = b' + s_a (c - b), s_b = swing(c~ - b', c' - b'), W_a' = s_a W_a, W_b' = s_b (s_a W_b)
//               (LoBSTr legs): the same rotations as Composed up to rounding; each pipeline keeps
//               the arithmetic its outputs were validated with;
//   Aim         each bone's own-frame axis (upper_axis, lower_axis) along its new direction and the
//               own-frame `side` axis as close as possible to the world `twist` (aim(); LoBSTr arms,
//               whose rotations follow the body rather than the predicted limb).
struct LimbRotation {
  enum class Rule { Composed, Sequential, Aim };
  Rule rule = Rule::Composed;
  Eigen::Vector3d upper_axis = Eigen::Vector3d::UnitX(), lower_axis = Eigen::Vector3d::UnitX();
  Eigen::Vector3d side = Eigen::Vector3d::UnitY(), twist = Eigen::Vector3d::UnitZ();

  static LimbRotation composed() noexcept { return {}; }
  static LimbRotation sequential() noexcept {
    LimbRotation r;
    r.rule = Rule::Sequential;
    return r;
  }
  static LimbRotation aimed(const Eigen::Vector3d& upper_axis, const Eigen::Vector3d& lower_axis, const Eigen::Vector3d& side,
                            const Eigen::Vector3d& twist) noexcept {
    return {Rule::Aim, upper_axis, lower_axis, side, twist};
  }
};

// New middle / end positions b', c' and the bones' world rotations W_a', W_b'. Rot is
// Eigen::Quaterniond or Eigen::Matrix3d (the caller's representation; a swing s applied to a matrix
// is s.toRotationMatrix() W).
template <class Rot>
struct LimbSolution {
  Eigen::Vector3d b, c;
  Rot upper, lower;
};

// s W in the representation of W.
template <class Rot>
inline Rot rotated(const Eigen::Quaterniond& s, const Rot& W) noexcept {
  if constexpr (std::is_same_v<Rot, Eigen::Quaterniond>) return s * W;
  else return s.toRotationMatrix() * W;
}

// Two-bone "limb to target" on the chain a -> b -> c (world positions; W_a, W_b the world
// rotations of a and b): the end goes to `target` (two_bone: clamped to the reach, bent towards
// `pole`), the bones' rotations follow by `rot`. The end joint's world rotation is the caller's
// (kept for a foot or a predicted hand, a tracker's for an aimed hand): see set_limb_locals.
template <class Rot>
inline LimbSolution<Rot> limb_to(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                 const Rot& Wa, const Rot& Wb, const Eigen::Vector3d& target, const Eigen::Vector3d& pole,
                                 const LimbRotation& rot = {}) noexcept {
  LimbSolution<Rot> out;
  two_bone(a, b, c, target, pole, out.b, out.c);
  if (rot.rule == LimbRotation::Rule::Aim) {
    const Eigen::Quaterniond Wu = aim(rot.upper_axis, rot.side, out.b - a, rot.twist);
    const Eigen::Quaterniond Wl = aim(rot.lower_axis, rot.side, out.c - out.b, rot.twist);
    if constexpr (std::is_same_v<Rot, Eigen::Quaterniond>) {
      out.upper = Wu;
      out.lower = Wl;
    } else {
      out.upper = Wu.toRotationMatrix();
      out.lower = Wl.toRotationMatrix();
    }
    return out;
  }
  const Eigen::Quaterniond sa = swing(b - a, out.b - a);
  out.upper = rotated(sa, Wa);
  if (rot.rule == LimbRotation::Rule::Composed) {
    const Eigen::Quaterniond sb = swing(sa * (c - b), out.c - out.b);
    out.lower = rotated(Eigen::Quaterniond(sb * sa), Wb);
  } else {
    const Eigen::Vector3d c_carried = out.b + sa * (c - b);
    out.lower = rotated(swing(c_carried - out.b, out.c - out.b), rotated(sa, Wb));
  }
  return out;
}

// The chain's local rotations from its new world rotations W_a', W_b', W_c (joints j[0..2], W_p
// the world rotation of a's parent, none for a root): L_a = W_p^-1 W_a', L_b = W_a'^-1 W_b',
// L_c = W_b'^-1 W_c. `normalize`: each local renormalised (LoBSTr) or left as the product
// (Neural3Points normalises the world rotations instead).
inline void set_limb_locals(BodyPose& pose, const int* j, const Eigen::Quaterniond* parent_world, const Eigen::Quaterniond& Wa,
                            const Eigen::Quaterniond& Wb, const Eigen::Quaterniond& Wc, bool normalize) noexcept {
  Eigen::Quaterniond L[3] = {parent_world ? Eigen::Quaterniond(parent_world->conjugate() * Wa) : Wa, Wa.conjugate() * Wb,
                             Wb.conjugate() * Wc};
  for (int k = 0; k < 3; ++k) pose.local[j[k]] = normalize ? L[k].normalized() : L[k];
}

}  // namespace sparsebody::pose
