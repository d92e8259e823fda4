// Recursive Newton-Euler inverse dynamics (Featherstone Table 5.1):
//   tau = M(q) qdd + C(q, qd) - J^T f_ext, gravity entering as a fictitious base acceleration a_0 = -g.
#pragma once
#include "sparsebody/dynamics/kinematics.hpp"

namespace sparsebody::dynamics {

// S_i^T f for body i, written into tau.
template <class S, int MB, int MD>
inline void project_force(const Model<S, MB, MD>& m, int i, const Vec6<S>& f, typename Model<S, MB, MD>::VecV& tau) {
  const Body<S>& b = m.bodies[i];
  switch (b.joint) {
    case JointType::Free: tau.template segment<6>(b.v_index) = f; break;
    case JointType::Spherical: tau.template segment<3>(b.v_index) = f.template head<3>(); break;
    case JointType::Revolute: tau(b.v_index) = b.axis.dot(f.template head<3>()); break;
    case JointType::Fixed: break;
  }
}

// Uses d.fext as external forces when d.has_ext (the K_ext part is ignored: RNEA is given qdd).
template <class S, int MB, int MD>
inline void rnea(const Model<S, MB, MD>& m, Data<S, MB, MD>& d, const typename Model<S, MB, MD>::VecQ& q,
                 const typename Model<S, MB, MD>::VecV& qd, const typename Model<S, MB, MD>::VecV& qdd,
                 typename Model<S, MB, MD>::VecV& tau) {
  forward_kinematics(m, d, q, &qd, false);
  Vec6<S> a0 = Vec6<S>::Zero();
  a0.template tail<3>() = -m.gravity;
  for (int i = 0; i < m.nb; ++i) {
    const int pi = m.bodies[i].parent;
    // a_i = X_i a_lambda + S_i qdd_i + c_i
    d.a[i] = d.X[i].apply(pi < 0 ? a0 : d.a[pi]) + joint_velocity(m, i, qdd) + d.c[i];
    const Mat6<S>& I = m.bodies[i].I;
    d.f[i] = mul6v(I, d.a[i]) + cross_force(d.v[i], mul6v(I, d.v[i]));
    if (d.has_ext) d.f[i] -= d.fext[i];
  }
  tau.resize(m.nv);
  for (int i = m.nb - 1; i >= 0; --i) {
    project_force(m, i, d.f[i], tau);
    const Body<S>& b = m.bodies[i];
    if (b.joint != JointType::Free && b.armature != S(0))  // rotor inertia: + armature qdd_i
      for (int r = 0; r < joint_nv(b.joint); ++r) tau(b.v_index + r) += b.armature * qdd(b.v_index + r);
    const int pi = b.parent;
    if (pi >= 0) d.f[pi] += d.X[i].apply_transpose_force(d.f[i]);
  }
}

}  // namespace sparsebody::dynamics
