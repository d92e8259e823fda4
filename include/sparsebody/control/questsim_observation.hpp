// QuestSim policy observation o = [o_sim, o_user, o_user,scale] (Winkler et al., SIGGRAPH Asia 2022,
// §3.3-§3.6), built from the simulated character and a window of sensor frames. Fixed size, no
// allocation, no exception. Python twin: weights_tool/questsim/observation.py (independent torch FK
// from the same model JSON and state; tests/questsim/test_parity.cpp compares the two).
//
// Frame S (§3.3): on the floor (y = 0, the simulator's ground plane through the origin, Y up) below
// the character's root (Hips), rotated about Y by the root's heading theta = atan2(f_x, f_z),
// f = R_root e_z (the avatar faces +Z in its reference pose; features::HeadingFrame). Everything
// Cartesian is expressed in S: a point p as R_S^T (p - o_S), a vector or rotation as R_S^T v,
// R_S^T R. Velocities are world velocities rotated into S (not relative to S's own motion).
// A root pointing straight up or down has no heading: theta = 0 there (HeadingFrame's convention).
//
// Layout for a model of NB bodies whose non-root joints have NJ velocity DoFs (NJ = nv - 6, the
// free root excluded: its pose is already in the link terms) and NF future sensor frames:
//
//   offset                    size        symbol            content
//   0                         NJ          o_sim,q           joint angles, joints in body order:
//                                                            spherical: rotation vector log(Q) (3),
//                                                            revolute: angle (1)
//   NJ                        NJ          o_sim,qd          joint velocities (= v without the root:
//                                                            spherical: child-frame angular velocity)
//   2NJ                       3 NB        o_sim,x           link positions in S (body origin = joint)
//   2NJ + 3NB                 6 NB        o_sim,R           link orientations in S: columns 0 then 1
//                                                            of R_S^T R_i (first two columns, §3.3)
//   2NJ + 9NB                 3 NB        o_sim,xd          link linear velocities (origin) in S
//   2NJ + 12NB                3 NB        o_sim,w           link angular velocities in S
//   2NJ + 15NB                6           o_f               contact force on the left, then right
//                                                            foot (Foot + Toes bodies, N) in S
//   2NJ + 15NB + 6            27 (NF+1)   o_user            frames t, t+1, ..., t+NF, each Eq. (2)
//                                                            [h_S, S R_h, l_S, S R_l, r_S, S R_r]:
//                                                            headset, left, right controller:
//                                                            position (3) + first two columns (6)
//   2NJ + 15NB + 6 + 27(NF+1) 1           o_user,scale      user height (m), Eq. (3)
//
// Size = 2 NJ + 15 NB + 6 + 27 (NF + 1) + 1 (quest_sim_observation_size). The paper's character
// (16 links, 33 DoF) gives o_sim = 312 exactly as stated in §3.3. For o_user the paper states both
// "6 future observations" and o_user in R^{6x3x9} = R^162; we follow the issue (current + 6 future
// = 7 frames, 189 values) and keep NF a template parameter (NF = 5 gives the paper's 162).
// The default sparsebody avatar (21 bodies, 48 non-root DoF) gives 96 + 315 + 6 + 189 + 1 = 607.
//
// Units are raw (rad, m, m/s, rad/s, N, m): any scaling belongs in the policy's weights file
// (input_mean / input_std, applied by nn::Network), not here.
// Why rotation vectors for o_sim,q: the paper's IsaacGym character has 3 hinge DoFs per ball joint
// whose angles it observes; our ball joints are quaternions, and log(Q) is the 3-number angle
// coordinate of the same joint (continuous up to pi, sign fixed by w >= 0).
#pragma once
#include <array>
#include <stdexcept>
#include <string>

#include "sparsebody/character/avatar.hpp"
#include "sparsebody/dynamics/kinematics.hpp"
#include "sparsebody/dynamics/simulator.hpp"
#include "sparsebody/features/heading_frame.hpp"

namespace sparsebody::control {

// Number of observation values for `bodies` links, `joint_dofs` non-root DoFs, `future` frames.
constexpr int quest_sim_observation_size(int bodies, int joint_dofs, int future = 6) {
  return 2 * joint_dofs + 15 * bodies + 6 + 27 * (future + 1) + 1;
}

// Offsets of each block (see the table above).
template <int NB, int NJ, int NF = 6>
struct QuestSimLayout {
  static constexpr int kBodies = NB, kJointDofs = NJ, kFuture = NF, kFrames = NF + 1;
  static constexpr int kUserFrameSize = 27;                 // 3 devices x (3 + 6)
  static constexpr int q = 0;                               // o_sim,q
  static constexpr int qd = q + NJ;                         // o_sim,qd
  static constexpr int x = qd + NJ;                         // o_sim,x
  static constexpr int R = x + 3 * NB;                      // o_sim,R
  static constexpr int xd = R + 6 * NB;                     // link linear velocities
  static constexpr int w = xd + 3 * NB;                     // link angular velocities
  static constexpr int f = w + 3 * NB;                      // o_f
  static constexpr int sim_size = f + 6;                    // |o_sim|
  static constexpr int user = sim_size;                     // o_user
  static constexpr int height = user + kFrames * kUserFrameSize;  // o_user,scale
  static constexpr int size = height + 1;
  static_assert(size == quest_sim_observation_size(NB, NJ, NF), "layout and size formula disagree");
};

// One sensor sample in world coordinates (the simulator's world = the OpenXR stage space: Y up,
// floor at y = 0): headset, left controller, right controller.
template <class S>
struct QuestSimDevicePose {
  dynamics::Vec3<S> position = dynamics::Vec3<S>::Zero();
  dynamics::Mat3<S> rotation = dynamics::Mat3<S>::Identity();  // columns = device axes in world
};
template <class S>
using QuestSimSensorFrame = std::array<QuestSimDevicePose<S>, 3>;  // 0 headset, 1 left, 2 right

// The same frame in another scalar type (clips are stored in double, the simulation runs in float).
template <class S, class T>
inline QuestSimSensorFrame<S> cast_sensor_frame(const QuestSimSensorFrame<T>& f) noexcept {
  QuestSimSensorFrame<S> out;
  for (int d = 0; d < 3; ++d) {
    out[d].position = f[d].position.template cast<S>();
    out[d].rotation = f[d].rotation.template cast<S>();
  }
  return out;
}

// Floor heading frame S of a root pose: origin o_S = (p_x, 0, p_z), rotation R_S = R_y(theta).
template <class S>
struct QuestSimFloorFrame {
  dynamics::Vec3<S> origin = dynamics::Vec3<S>::Zero();
  S c = S(1), s = S(0);  // cos theta, sin theta

  static QuestSimFloorFrame from_root(const dynamics::Mat3<S>& R_root, const dynamics::Vec3<S>& p_root) noexcept {
    const dynamics::Vec3<S> fwd = R_root.col(2);
    const features::HeadingFrame h = features::HeadingFrame::from(
        Eigen::Vector3d(double(p_root.x()), 0.0, double(p_root.z())),
        Eigen::Vector3d(double(fwd.x()), double(fwd.y()), double(fwd.z())));
    QuestSimFloorFrame f;
    f.origin = dynamics::Vec3<S>(p_root.x(), S(0), p_root.z());
    f.c = S(std::cos(h.theta));
    f.s = S(std::sin(h.theta));
    return f;
  }
  // R_S^T v, R_y(theta) = [c 0 s; 0 1 0; -s 0 c].
  dynamics::Vec3<S> vector(const dynamics::Vec3<S>& v) const noexcept {
    return dynamics::Vec3<S>(c * v.x() - s * v.z(), v.y(), s * v.x() + c * v.z());
  }
  dynamics::Vec3<S> point(const dynamics::Vec3<S>& p) const noexcept { return vector(p - origin); }
};

// Writes a position (3) and the first two columns of the rotation (6), both in S.
template <class S, class T>
inline void write_pose6(const QuestSimFloorFrame<S>& fs, const dynamics::Vec3<S>& p, const dynamics::Mat3<S>& R,
                       T* pos, T* rot6) noexcept {
  const dynamics::Vec3<S> ps = fs.point(p), c0 = fs.vector(R.col(0)), c1 = fs.vector(R.col(1));
  for (int k = 0; k < 3; ++k) {
    pos[k] = static_cast<T>(ps(k));
    rot6[k] = static_cast<T>(c0(k));
    rot6[3 + k] = static_cast<T>(c1(k));
  }
}

// Builds the observation of a character whose kinematics (d.R, d.p, d.v) match (q, v). `foot_force`
// are the world contact forces on the left and right foot; `user[k]` is the sensor frame t + k.
// `out` receives QuestSimLayout<NB, NJ, NF>::size values. The model must have NB bodies, a free
// root (body 0) and nv = NJ + 6 (QuestSimObservationBuilder checks this once).
template <int NB, int NJ, int NF, class S, int MB, int MD, class T>
inline void build_quest_sim_observation(const dynamics::Model<S, MB, MD>& m, const dynamics::Data<S, MB, MD>& d,
                                     const typename dynamics::Model<S, MB, MD>::VecQ& q,
                                     const typename dynamics::Model<S, MB, MD>::VecV& v,
                                     const std::array<dynamics::Vec3<S>, 2>& foot_force,
                                     const std::array<QuestSimSensorFrame<S>, NF + 1>& user, S user_height,
                                     T* out) noexcept {
  using L = QuestSimLayout<NB, NJ, NF>;
  using dynamics::JointType;
  using V3 = dynamics::Vec3<S>;
  const QuestSimFloorFrame<S> fs = QuestSimFloorFrame<S>::from_root(d.R[0], d.p[0]);
  // o_sim,q and o_sim,qd: non-root joints in body order (v_index - 6 is the slot).
  for (int i = 1; i < NB; ++i) {
    const dynamics::Body<S>& b = m.bodies[i];
    const int k = b.v_index - 6;
    if (b.joint == JointType::Spherical) {
      const V3 r = dynamics::quat_log(dynamics::read_quat<S>(q, b.q_index));
      for (int a = 0; a < 3; ++a) {
        out[L::q + k + a] = static_cast<T>(r(a));
        out[L::qd + k + a] = static_cast<T>(v(b.v_index + a));
      }
    } else if (b.joint == JointType::Revolute) {
      out[L::q + k] = static_cast<T>(q(b.q_index));
      out[L::qd + k] = static_cast<T>(v(b.v_index));
    }
  }
  // Links: x, R (6D), linear and angular velocity, all in S.
  for (int i = 0; i < NB; ++i) {
    write_pose6(fs, d.p[i], d.R[i], out + L::x + 3 * i, out + L::R + 6 * i);
    const V3 vl = fs.vector(d.R[i] * V3(d.v[i].template tail<3>()));
    const V3 w = fs.vector(d.R[i] * V3(d.v[i].template head<3>()));
    for (int a = 0; a < 3; ++a) {
      out[L::xd + 3 * i + a] = static_cast<T>(vl(a));
      out[L::w + 3 * i + a] = static_cast<T>(w(a));
    }
  }
  // o_f: left then right foot.
  for (int side = 0; side < 2; ++side) {
    const V3 f = fs.vector(foot_force[side]);
    for (int a = 0; a < 3; ++a) out[L::f + 3 * side + a] = static_cast<T>(f(a));
  }
  // o_user: frames t .. t+NF, devices headset, left, right (Eq. 2).
  for (int t = 0; t <= NF; ++t)
    for (int dev = 0; dev < 3; ++dev) {
      T* o = out + L::user + L::kUserFrameSize * t + 9 * dev;
      write_pose6(fs, user[t][dev].position, user[t][dev].rotation, o, o + 3);
    }
  out[L::height] = static_cast<T>(user_height);  // Eq. (3)
}

// Binds the observation to one model: checks its shape once (constructor, may throw) and knows
// which bodies form each foot. build() is the per-step call.
template <class S, int MB, int MD, int NB = character::kDefaultAvatarBodies, int NJ = character::kDefaultAvatarJointDofs, int NF = 6>
class QuestSimObservationBuilder {
 public:
  using Layout = QuestSimLayout<NB, NJ, NF>;
  using ModelT = dynamics::Model<S, MB, MD>;
  using UserWindow = std::array<QuestSimSensorFrame<S>, NF + 1>;
  static constexpr int kSize = Layout::size;

  // Foot bodies by name: "Foot_L", "Toes_L" (left) and "Foot_R", "Toes_R" (right); absent names
  // are skipped (a model without toes works), but each side needs at least one body.
  explicit QuestSimObservationBuilder(const ModelT& m) {
    if (m.nb != NB || m.nv != NJ + 6 || m.nb == 0 || m.root_body() != 0)
      throw std::invalid_argument("QuestSimObservationBuilder: model has " + std::to_string(m.nb) + " bodies and nv " +
                                  std::to_string(m.nv) + " (free root expected), the layout is for " +
                                  std::to_string(NB) + " bodies and nv " + std::to_string(NJ + 6));
    foot_of_body_.fill(-1);
    const char* names[2][2] = {{"Foot_L", "Toes_L"}, {"Foot_R", "Toes_R"}};
    for (int side = 0; side < 2; ++side) {
      bool any = false;
      for (const char* n : names[side]) {
        const int b = m.find(n);
        if (b >= 0) { foot_of_body_[b] = side; any = true; }
      }
      if (!any) throw std::invalid_argument(std::string("QuestSimObservationBuilder: no body named ") + names[side][0]);
    }
  }

  // Sum of the contact forces of the simulator's last step on each foot (world, N).
  template <int MC, int MBox>
  std::array<dynamics::Vec3<S>, 2> foot_forces(const dynamics::Simulator<S, MB, MD, MC, MBox>& sim) const noexcept {
    std::array<dynamics::Vec3<S>, 2> f{dynamics::Vec3<S>::Zero(), dynamics::Vec3<S>::Zero()};
    for (int k = 0; k < sim.num_contacts(); ++k) {
      const auto& c = sim.contact_at(k);
      const int side = foot_of_body_[c.body];
      if (side >= 0 && c.active) f[side] += c.force;
    }
    return f;
  }
  int foot_of_body(int body) const noexcept { return foot_of_body_[body]; }

  // The observation of the simulator's current state (T = the policy's scalar).
  template <class T, int MC, int MBox>
  void build(const dynamics::Simulator<S, MB, MD, MC, MBox>& sim, const UserWindow& user, S user_height,
             T* out) const noexcept {
    build_quest_sim_observation<NB, NJ, NF>(sim.model(), sim.data(), sim.q(), sim.v(), foot_forces(sim), user,
                                         user_height, out);
  }

 private:
  std::array<int, MB> foot_of_body_{};
};

}  // namespace sparsebody::control
