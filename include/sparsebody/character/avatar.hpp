// Default avatar generated from height and mass with de Leva (1996) segment parameters.
// Topology of the training mocap skeleton (Bandai Namco dataset): Hips (free root), Spine, Chest,
// Neck, Head, Shoulder_L/R, UpperArm_L/R, LowerArm_L/R, Hand_L/R, UpperLeg_L/R, LowerLeg_L/R,
// Foot_L/R, Toes_L/R. The mocap's joint_Root is the ground reference frame, not a body.
// Reference pose: T-pose, Y up, facing +Z (character's left is +X), every joint frame aligned with
// the world, so a BVH local rotation is directly the joint quaternion.
//
// Where de Leva has no segment we split one (documented choices, not measurements):
//   Neck = 15 % of the head segment mass (the head segment runs from vertex to C7);
//   Shoulder_L/R (clavicle/scapula) = 10 % each of the upper-trunk mass;
//   Toes = 20 % of the foot mass.
// Leg lengths are rescaled together so the ankle sits 4 % of stature above the floor (de Leva's
// head + trunk + thigh + shank leave only 2 % for the ankle height).
#pragma once
#include <algorithm>
#include <cmath>
#include <string>

#include "sparsebody/dynamics/model.hpp"
#include "sparsebody/character/de_leva.hpp"

namespace sparsebody::character {

// Size of the default avatar (default_avatar below): 21 bodies; nv = 54, i.e. 48 DoFs besides the
// free root (hinge knees, elbows and toes, spherical joints elsewhere). Fixed-size users (the
// QuestSim observation) take these as template arguments; test_avatar checks them.
inline constexpr int kDefaultAvatarBodies = 21;
inline constexpr int kDefaultAvatarJointDofs = 48;

struct AvatarOptions {
  double height = 1.75;           // m (Neural3Points: 1.75 m, 63 kg)
  double mass = 63.0;             // kg
  double kp = 200.0, kd = 20.0;   // servo gains on every actuated joint
  double torque_limit = 300.0;    // N m per joint (norm for spherical joints); 0 = unlimited
  bool hinge_knees_elbows = true; // revolute knees/elbows (else spherical like the mocap)
  bool fixed_root = false;        // weld the Hips to the world (testing, upper-body use)
};

namespace detail {

// Builds the default avatar: segment sizes from de Leva scaled to the height (length scale
// s = height / 1.741 m), landmark heights of the reference pose, then the trunk chain, the arms and
// the legs in that body order (Hips, Spine, Chest, Neck, Head, then per side L, R: Shoulder,
// UpperArm, LowerArm, Hand; then per side UpperLeg, LowerLeg, Foot, Toes).
template <class S, int MB, int MD>
class AvatarBuilder {
 public:
  using V = dynamics::Vec3<S>;
  using Segment = de_leva::Segment;

  explicit AvatarBuilder(const AvatarOptions& o)
      : o_(o), s_(o.height / (de_leva::kStatureMm / 1000.0)), mass_(o.mass), height_(S(o.height)) {
    namespace dl = de_leva;
    // Landmark heights (world y) in the reference pose, from the top of the head down.
    const S y_c7 = height_ - length(dl::kHead);
    const S y_xyph = y_c7 - length(dl::kUpperTrunk);
    const S y_omph = y_xyph - length(dl::kMiddleTrunk);
    y_midh_ = y_omph - length(dl::kLowerTrunk);
    ankle_h_ = S(0.04) * height_;
    const double leg_k = double(y_midh_ - ankle_h_) / double(length(dl::kThigh) + length(dl::kShank));
    l_thigh_ = S(leg_k) * length(dl::kThigh);
    l_shank_ = S(leg_k) * length(dl::kShank);
    m_.name = "sparsebody_avatar";
  }

  dynamics::Model<S, MB, MD> build() {
    const int chest = add_trunk();
    for (int side = 0; side < 2; ++side) add_arm(side, chest);  // L = +x
    for (int side = 0; side < 2; ++side) add_leg(side);
    return m_;
  }

 private:
  using Body = dynamics::Body<S>;
  using Mat3 = dynamics::Mat3<S>;
  using JointType = dynamics::JointType;

  S length(const Segment& g) const { return S(g.length_mm / 1000.0 * s_); }
  S scaled(double metres) const { return S(metres * s_); }
  JointType elbow_knee() const { return o_.hinge_knees_elbows ? JointType::Revolute : JointType::Spherical; }

  // Principal inertia from radii of gyration; `axis` = the segment's long axis (0 x, 1 y, 2 z).
  // Sagittal axis = anteroposterior (z); transverse = the remaining one.
  static Mat3 inertia(double mass, const Segment& g, int axis, double len) {
    Mat3 I = Mat3::Zero();
    const double rs = g.r_sag * len, rt = g.r_trans * len, rl = g.r_long * len;
    if (axis == 1) { I(0, 0) = mass * rt * rt; I(1, 1) = mass * rl * rl; I(2, 2) = mass * rs * rs; }
    else if (axis == 0) { I(0, 0) = mass * rl * rl; I(1, 1) = mass * rt * rt; I(2, 2) = mass * rs * rs; }
    else { I(0, 0) = mass * rt * rt; I(1, 1) = mass * rs * rs; I(2, 2) = mass * rl * rl; }
    return I;
  }
  // A body; actuated joints get the options' servo gains and torque limit.
  Body body(int parent, JointType jt, V pos, double mass, V com, const Mat3& I) const {
    Body b;
    b.parent = parent; b.joint = jt; b.pos = pos; b.mass = S(mass); b.com = com; b.inertia = I;
    if (jt != JointType::Free && jt != JointType::Fixed) {
      b.kp = S(o_.kp); b.kd = S(o_.kd); b.torque_limit = S(o_.torque_limit);
    }
    return b;
  }
  static void capsule(Body& b, V a, V c, S r) {
    dynamics::Shape<S>& sh = b.shapes[b.num_shapes++];
    sh.type = dynamics::Shape<S>::Type::Capsule; sh.pos = a; sh.pos2 = c; sh.radius = r;
  }
  static void sphere(Body& b, V c, S r) {
    dynamics::Shape<S>& sh = b.shapes[b.num_shapes++];
    sh.type = dynamics::Shape<S>::Type::Sphere; sh.pos = c; sh.radius = r;
  }
  static void box(Body& b, V c, V h) {
    dynamics::Shape<S>& sh = b.shapes[b.num_shapes++];
    sh.type = dynamics::Shape<S>::Type::Box; sh.pos = c; sh.half = h;
  }

  // Hips (free root), Spine, Chest, Neck, Head; returns the Chest's index.
  int add_trunk() {
    namespace dl = de_leva;
    {  // Hips = de Leva lower trunk (omphalion..mid-hip); origin at mid-hip.
      const S l = length(dl::kLowerTrunk);
      Body b = body(-1, o_.fixed_root ? JointType::Fixed : JointType::Free, V(0, y_midh_, 0),
                    dl::kLowerTrunk.mass_fraction * mass_, V(0, S(1 - dl::kLowerTrunk.com) * l, 0),
                    inertia(dl::kLowerTrunk.mass_fraction * mass_, dl::kLowerTrunk, 1, l));
      capsule(b, V(-scaled(0.07), S(0.35) * l, 0), V(scaled(0.07), S(0.35) * l, 0), scaled(0.09));
      m_.add_body("Hips", b);
    }
    {  // Spine = middle trunk (xiphoid..omphalion), origin at omphalion
      const S l = length(dl::kMiddleTrunk);
      Body b = body(0, JointType::Spherical, V(0, length(dl::kLowerTrunk), 0), dl::kMiddleTrunk.mass_fraction * mass_,
                    V(0, S(1 - dl::kMiddleTrunk.com) * l, 0), inertia(dl::kMiddleTrunk.mass_fraction * mass_, dl::kMiddleTrunk, 1, l));
      sphere(b, V(0, S(0.5) * l, 0), scaled(0.1));
      m_.add_body("Spine", b);
    }
    int chest;
    {  // Chest = upper trunk minus the two shoulders, origin at xiphoid
      const double chest_mass = dl::kUpperTrunk.mass_fraction * mass_ * 0.8;
      const S l = length(dl::kUpperTrunk);
      Body b = body(1, JointType::Spherical, V(0, length(dl::kMiddleTrunk), 0), chest_mass,
                    V(0, S(1 - dl::kUpperTrunk.com) * l, 0), inertia(chest_mass, dl::kUpperTrunk, 1, l));
      capsule(b, V(-scaled(0.08), S(0.5) * l, 0), V(scaled(0.08), S(0.5) * l, 0), scaled(0.1));
      chest = m_.add_body("Chest", b);
    }
    const double head_seg = dl::kHead.mass_fraction * mass_;
    const S l_head = length(dl::kHead), l_neck = S(0.35) * l_head;
    {  // Neck: lower 35 % of the head segment length, 15 % of its mass
      const double mass = 0.15 * head_seg;
      Body b = body(chest, JointType::Spherical, V(0, length(dl::kUpperTrunk), 0), mass, V(0, S(0.5) * l_neck, 0),
                    inertia(mass, Segment{0, 0, 0, 0.3, 0.3, 0.3}, 1, double(l_neck)));
      m_.add_body("Neck", b);
    }
    {  // Head: CoM from de Leva (59.76 % from the vertex) re-expressed from the head joint
      const double mass = 0.85 * head_seg;
      const S com_y = (S(1) - S(dl::kHead.com)) * l_head - l_neck;
      Body b = body(3, JointType::Spherical, V(0, l_neck, 0), mass, V(0, std::max(com_y, S(0.3) * (l_head - l_neck)), 0),
                    inertia(mass, dl::kHead, 1, double(l_head)));
      sphere(b, V(0, S(0.45) * (l_head - l_neck), scaled(0.01)), scaled(0.1));
      m_.add_body("Head", b);
    }
    return chest;
  }

  // Shoulder (clavicle/scapula: 10 % of the upper trunk), UpperArm, LowerArm (hinge about y), Hand.
  void add_arm(int side, int chest) {
    namespace dl = de_leva;
    const S sx = side == 0 ? S(1) : S(-1);
    const std::string suf = side == 0 ? "_L" : "_R";
    const S sh_x = scaled(0.03), arm_x = scaled(0.175), sh_drop = scaled(0.035);
    const double sh_mass = dl::kUpperTrunk.mass_fraction * mass_ * 0.1;
    Body sh = body(chest, JointType::Spherical, V(sx * sh_x, length(dl::kUpperTrunk) - sh_drop, 0), sh_mass,
                   V(sx * S(0.5) * (arm_x - sh_x), 0, 0),
                   inertia(sh_mass, Segment{0, 0, 0, 0.3, 0.3, 0.15}, 0, double(arm_x - sh_x)));
    const int ish = m_.add_body("Shoulder" + suf, sh);
    const S lu = length(dl::kUpperArm), lf = length(dl::kForearm), lh = length(dl::kHand);
    const double mu = dl::kUpperArm.mass_fraction * mass_, mf = dl::kForearm.mass_fraction * mass_, mh = dl::kHand.mass_fraction * mass_;
    Body ua = body(ish, JointType::Spherical, V(sx * (arm_x - sh_x), 0, 0), mu, V(sx * S(dl::kUpperArm.com) * lu, 0, 0),
                   inertia(mu, dl::kUpperArm, 0, double(lu)));
    capsule(ua, V(sx * S(0.1) * lu, 0, 0), V(sx * S(0.9) * lu, 0, 0), scaled(0.045));
    const int iua = m_.add_body("UpperArm" + suf, ua);
    Body la = body(iua, elbow_knee(), V(sx * lu, 0, 0), mf, V(sx * S(dl::kForearm.com) * lf, 0, 0),
                   inertia(mf, dl::kForearm, 0, double(lf)));
    la.axis = V::UnitY();
    capsule(la, V(sx * S(0.1) * lf, 0, 0), V(sx * S(0.9) * lf, 0, 0), scaled(0.04));
    const int ila = m_.add_body("LowerArm" + suf, la);
    Body hd = body(ila, JointType::Spherical, V(sx * lf, 0, 0), mh, V(sx * S(dl::kHand.com) * lh, 0, 0),
                   inertia(mh, dl::kHand, 0, double(lh)));
    capsule(hd, V(sx * S(0.3) * lh, 0, 0), V(sx * S(1.2) * lh, 0, 0), scaled(0.035));
    m_.add_body("Hand" + suf, hd);
  }

  // UpperLeg, LowerLeg (hinge about x), Foot (heel..metatarsophalangeal joint, sole at the floor in
  // the reference pose; 80 % of de Leva's foot), Toes (revolute about x; 20 %).
  void add_leg(int side) {
    namespace dl = de_leva;
    const S sx = side == 0 ? S(1) : S(-1);
    const std::string suf = side == 0 ? "_L" : "_R";
    const S hip_x = scaled(0.085);
    const S lfoot = length(dl::kFoot);
    const S heel_z = S(-0.22) * lfoot, mtp_z = S(0.51) * lfoot, toe_z = S(0.78) * lfoot;
    const S foot_hw = scaled(0.045), toe_h = scaled(0.025);
    const double mt = dl::kThigh.mass_fraction * mass_, ms = dl::kShank.mass_fraction * mass_;
    const double mfoot = dl::kFoot.mass_fraction * mass_ * 0.8, mtoe = dl::kFoot.mass_fraction * mass_ * 0.2;
    Body th = body(0, JointType::Spherical, V(sx * hip_x, 0, 0), mt, V(0, -S(dl::kThigh.com) * l_thigh_, 0),
                   inertia(mt, dl::kThigh, 1, double(l_thigh_)));
    capsule(th, V(0, S(-0.15) * l_thigh_, 0), V(0, S(-0.9) * l_thigh_, 0), scaled(0.065));
    const int ith = m_.add_body("UpperLeg" + suf, th);
    Body sk = body(ith, elbow_knee(), V(0, -l_thigh_, 0), ms, V(0, -S(dl::kShank.com) * l_shank_, 0),
                   inertia(ms, dl::kShank, 1, double(l_shank_)));
    sk.axis = V::UnitX();
    capsule(sk, V(0, S(-0.1) * l_shank_, 0), V(0, S(-0.85) * l_shank_, 0), scaled(0.05));
    const int isk = m_.add_body("LowerLeg" + suf, sk);
    Body ft = body(isk, JointType::Spherical, V(0, -l_shank_, 0), mfoot,
                   V(0, S(-0.6) * ankle_h_, heel_z + S(0.4) * lfoot), inertia(mfoot, dl::kFoot, 2, double(lfoot)));
    box(ft, V(0, S(-0.5) * ankle_h_, S(0.5) * (heel_z + mtp_z)), V(foot_hw, S(0.5) * ankle_h_, S(0.5) * (mtp_z - heel_z)));
    const int ift = m_.add_body("Foot" + suf, ft);
    Body to = body(ift, JointType::Revolute, V(0, -ankle_h_ + toe_h, mtp_z), mtoe, V(0, S(-0.5) * toe_h, S(0.5) * (toe_z - mtp_z)),
                   inertia(mtoe, Segment{0, 0, 0, 0.3, 0.3, 0.2}, 2, double(toe_z - mtp_z)));
    to.axis = V::UnitX();
    box(to, V(0, S(-0.5) * toe_h, S(0.5) * (toe_z - mtp_z)), V(foot_hw, S(0.5) * toe_h, S(0.5) * (toe_z - mtp_z)));
    m_.add_body("Toes" + suf, to);
  }

  AvatarOptions o_;
  double s_;   // length scale, height / de Leva's reference stature
  double mass_;   // total mass (kg)
  S height_;        // height (m)
  // Mid-hip height in the reference pose, ankle height, leg lengths rescaled to fit between them.
  S y_midh_, ankle_h_, l_thigh_, l_shank_;
  dynamics::Model<S, MB, MD> m_;
};

}  // namespace detail

template <class S, int MB = 24, int MD = 72>
inline dynamics::Model<S, MB, MD> default_avatar(const AvatarOptions& o = AvatarOptions{}) {
  return detail::AvatarBuilder<S, MB, MD>(o).build();
}

// QuestSim-style scaling (Winkler et al. 2022, sec. 3.6 / 5.4): every length (joint offsets,
// centres of mass, collision geometry) scales by `factor`; mass by factor^mass_exponent
// (3 = constant density, the default; 1 = mass proportional to height) and rotational inertia by
// factor^(mass_exponent + 2). scale_model_into is the same in place: `out` (which must have in's
// tree, e.g. an earlier scaling of it) takes only the numbers, so it never allocates (a pipeline
// resizing its avatar for a new user at run time). False when the trees differ.
template <class S, int MB, int MD>
inline bool scale_model_into(const dynamics::Model<S, MB, MD>& in, S factor, dynamics::Model<S, MB, MD>& out,
                             S mass_exponent = S(3)) noexcept {
  if (!out.assign_parameters(in)) return false;
  const S km = std::pow(factor, mass_exponent);
  for (int i = 0; i < out.nb; ++i) {
    auto& b = out.bodies[i];
    b.pos *= factor; b.com *= factor; b.mass *= km; b.inertia *= km * factor * factor;
    for (int k = 0; k < b.num_shapes; ++k) {
      b.shapes[k].pos *= factor; b.shapes[k].pos2 *= factor; b.shapes[k].half *= factor; b.shapes[k].radius *= factor;
    }
  }
  out.finalize();
  return true;
}

template <class S, int MB, int MD>
inline dynamics::Model<S, MB, MD> scale_model(const dynamics::Model<S, MB, MD>& in, S factor, S mass_exponent = S(3)) {
  dynamics::Model<S, MB, MD> m = in;
  scale_model_into(in, factor, m, mass_exponent);
  return m;
}

// The default (1.75 m) avatar scaled to a user's height, as QuestSim initialises its character from
// the headset height (PD gains kept; users can rescale them with the mass).
template <class S, int MB = 24, int MD = 72>
inline dynamics::Model<S, MB, MD> avatar_for_user_height(double user_height, AvatarOptions o = AvatarOptions{}) {
  const double ref = o.height;
  return scale_model(default_avatar<S, MB, MD>(o), S(user_height / ref));
}

}  // namespace sparsebody::character
