// Recursive Newton-Euler inverse dynamics (Featherstone Table 5.1):
//   tau = M(q) qdd + C(q, qd) - J^T f_ext, gravity entering as a fictitious base acceleration a_0 = -g.
#pragma once
#include "sparsebody/dynamics/kinematics.hpp"

namespace sparsebody::dynamics {

// Uses d.fext as external forces when d.has_ext (the K_ext part is ignored: RNEA is given qdd).
// Both passes keep each body's spatial vectors in scalars (the same reason as joint_transform: Eigen
// Vec6 temporaries written by scalar stores and read back by packed loads stalled on store
// forwarding) and use the rigid inertia's structure (mul_rigid_inertia): 0.59 -> 0.50 us on the
// 34-DoF humanoid (x86-64-v3, Zen 4). I a and I v share one two-lane product (Lanes2): -8 %.
template <class S, int MB, int MD>
inline void rnea(const Model<S, MB, MD>& m, Data<S, MB, MD>& d, const typename Model<S, MB, MD>::VecQ& q,
                 const typename Model<S, MB, MD>::VecV& qd, const typename Model<S, MB, MD>::VecV& qdd,
                 typename Model<S, MB, MD>::VecV& tau) {
  forward_kinematics(m, d, q, &qd, false);
  tau.resize(m.nv);
  for (int i = 0; i < m.nb; ++i) {
    const Body<S>& b = m.bodies[i];
    const int pi = b.parent;
    S in[6];  // a_lambda (a_0 = -g at the root)
    if (pi < 0) {
      in[0] = in[1] = in[2] = S(0);
      in[3] = -m.gravity.x();
      in[4] = -m.gravity.y();
      in[5] = -m.gravity.z();
    } else {
      const Vec6<S>& ap = d.a[pi];
      SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) in[r] = ap(r);
    }
    // a_i = X_i a_lambda + S_i qdd_i + c_i
    S a[6];
    d.X[i].apply(in, a);
    SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) a[r] += d.c[i](r);
    const int k = b.v_index;
    switch (b.joint) {
      case JointType::Free: SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) a[r] += qdd(k + r); break;
      case JointType::Spherical: SPARSEBODY_UNROLL for (int r = 0; r < 3; ++r) a[r] += qdd(k + r); break;
      case JointType::Revolute: {
        const S x = qdd(k);
        a[0] += b.axis.x() * x;
        a[1] += b.axis.y() * x;
        a[2] += b.axis.z() * x;
        break;
      }
      case JointType::Fixed: break;
    }
    Vec6<S>& ai = d.a[i];
    SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) ai(r) = a[r];
    // f_i = I_i a_i + v_i x* I_i v_i - f_ext; I_i a_i and I_i v_i in the two lanes of one product
    S v[6], Iv[6], vf[6];
    Lanes2<S> av[6], Iav[6];
    SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) {
      v[r] = d.v[i](r);
      av[r] = Lanes2Of<S>::make(a[r], v[r]);
    }
    mul_rigid_inertia(b.I, av, Iav);
    SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) Iv[r] = Iav[r][1];
    cross_force(v, Iv, vf);
    Vec6<S>& f = d.f[i];
    SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) f(r) = Iav[r][0] + vf[r];
    if (d.has_ext) f -= d.fext[i];
  }
  for (int i = m.nb - 1; i >= 0; --i) {
    const Body<S>& b = m.bodies[i];
    S f[6];
    SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) f[r] = d.f[i](r);
    const int k = b.v_index;
    switch (b.joint) {  // tau_i = S_i^T f_i (+ armature qdd_i: rotor inertia)
      case JointType::Free: SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) tau(k + r) = f[r]; break;
      case JointType::Spherical: SPARSEBODY_UNROLL for (int r = 0; r < 3; ++r) tau(k + r) = f[r] + b.armature * qdd(k + r); break;
      case JointType::Revolute: tau(k) = b.axis.x() * f[0] + b.axis.y() * f[1] + b.axis.z() * f[2] + b.armature * qdd(k); break;
      case JointType::Fixed: break;
    }
    if (b.parent < 0) continue;
    S o[6];  // f_lambda += X_i^T f_i
    d.X[i].apply_transpose_force(f, o);
    Vec6<S>& fp = d.f[b.parent];
    SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) fp(r) += o[r];
  }
}

}  // namespace sparsebody::dynamics
