// PD servos (Neural3Points: kp = 200, kd = 20 on every joint at 120 Hz).
// Targets use the configuration layout: a quaternion (w, x, y, z) per spherical joint, an angle per
// revolute joint (free/fixed entries ignored). The spherical error is the rotation vector of
// q^-1 q_target, i.e. expressed in the child frame like the joint velocity:
//   tau = kp log(q^-1 q*) + kd (qd* - qd) - damping qd,
// clamped to torque_limit (vector norm for spherical joints). This is the explicit part; the
// damping of the next velocity, -h (kd + damping) qdd, is added implicitly inside ABA (D_i) through
// implicit_damping_diagonal below.
#pragma once
#include "sparsebody/dynamics/kinematics.hpp"

namespace sparsebody::dynamics {

template <class S, int MB, int MD>
inline void pd_torques(const Model<S, MB, MD>& m, const typename Model<S, MB, MD>::VecQ& q,
                      const typename Model<S, MB, MD>::VecV& qd, const typename Model<S, MB, MD>::VecQ& q_target,
                      const typename Model<S, MB, MD>::VecV& qd_target, typename Model<S, MB, MD>::VecV& tau) {
  tau.setZero(m.nv);
  for (int i = 0; i < m.nb; ++i) {
    const Body<S>& b = m.bodies[i];
    switch (b.joint) {
      case JointType::Spherical: {
        const Quat<S> cur = read_quat<S>(q, b.q_index), tgt = read_quat<S>(q_target, b.q_index);
        const Vec3<S> e = quat_log(Quat<S>(cur.conjugate() * tgt));
        const Vec3<S> w = qd.template segment<3>(b.v_index);
        Vec3<S> t = b.kp * e + b.kd * (Vec3<S>(qd_target.template segment<3>(b.v_index)) - w);
        const S n = t.norm();
        if (b.torque_limit > S(0) && n > b.torque_limit) t *= b.torque_limit / n;
        tau.template segment<3>(b.v_index) = t - b.damping * w;
        break;
      }
      case JointType::Revolute: {
        const int k = b.v_index;
        S t = b.kp * (q_target(b.q_index) - q(b.q_index)) + b.kd * (qd_target(k) - qd(k));
        if (b.torque_limit > S(0)) t = std::max(-b.torque_limit, std::min(b.torque_limit, t));
        tau(k) = t - b.damping * qd(k);
        break;
      }
      case JointType::Free:
        tau.template segment<6>(b.v_index) = -b.damping * qd.template segment<6>(b.v_index);
        break;
      case JointType::Fixed: break;
    }
  }
}

// Passive damping only (torque-driven use): tau = -damping qd.
template <class S, int MB, int MD>
inline void passive_torques(const Model<S, MB, MD>& m, const typename Model<S, MB, MD>::VecV& qd,
                           typename Model<S, MB, MD>::VecV& tau) {
  tau.setZero(m.nv);
  for (int i = 0; i < m.nb; ++i) {
    const Body<S>& b = m.bodies[i];
    for (int k = 0; k < joint_nv(b.joint); ++k) tau(b.v_index + k) = -b.damping * qd(b.v_index + k);
  }
}

// The implicit part of the servo and passive damping, Data::implicit_diagonal for ABA:
// h (kd + damping) on every DoF of a spherical or revolute joint (h damping alone when include_kd
// is false: torque-driven use). The free root's entries are zero here (its passive damping stays
// explicit); the root servo writes its h K_r there.
template <class S, int MB, int MD>
inline void implicit_damping_diagonal(const Model<S, MB, MD>& m, S h, bool include_kd,
                                      typename Model<S, MB, MD>::VecV& diag) {
  diag.resize(m.nv);
  for (int i = 0; i < m.nb; ++i) {
    const Body<S>& b = m.bodies[i];
    const S k = b.joint == JointType::Free ? S(0) : h * ((include_kd ? b.kd : S(0)) + b.damping);
    for (int r = 0; r < joint_nv(b.joint); ++r) diag(b.v_index + r) = k;
  }
}

}  // namespace sparsebody::dynamics
