// Articulated-body algorithm (Featherstone Table 7.1) with implicit joint damping.
//
// Implicit damping: the servo/passive damping torque is evaluated at the next velocity,
// tau_d = -Kd (qd + h qdd), so the dynamics become (M + h Kd) qdd = tau - C with tau holding the
// explicit part (-Kd qd). Only ABA's joint-space term changes:
//   D_i = S_i^T I^A_i S_i + h Kd_i,   u_i = tau_i - S_i^T p^A_i,
// and the same D_i is used in the parent update I^a_i = I^A_i - U_i D_i^-1 U_i^T, so the result is
// exactly the (M + h Kd)^-1 solve (this is what the CRBA test checks). Kd_i = (kd_i + damping_i) I.
//
// Optional root servo damping K_r = diag(kr_w I3, kr_v I3) on the free root's 6 DoFs (a PD servo on
// the root, e.g. a residual wrench toward a reference root, dynamics/simulator.hpp RootServo): the
// same implicit form, D_root = I^A_root + h K_r. The root's joint force is I^A a + p^A with
// a = qdd + a' (a' = X a_0: gravity), so (I^A + h K_r) a = tau - p^A + h K_r a'.
#pragma once
#include "sparsebody/dynamics/kinematics.hpp"

namespace sparsebody::dynamics {

// Pass 1: kinematics plus the per-body velocity-product force v x* I v.
template <class S, int MB, int MD>
inline void aba_kinematics(const Model<S, MB, MD>& m, Data<S, MB, MD>& d, const typename Model<S, MB, MD>::VecQ& q,
                          const typename Model<S, MB, MD>::VecV& qd, bool with_world = false) {
  forward_kinematics(m, d, q, &qd, with_world);
  for (int i = 0; i < m.nb; ++i) d.bias[i] = cross_force(d.v[i], mul6v(m.bodies[i].I, d.v[i]));
}

// Passes 2 and 3, after aba_kinematics. h_damp = h for implicit damping, 0 for explicit.
// When include_kd is false only the passive damping is implicit (torque-driven use).
// root_damping: K_r's diagonal (angular then linear, free-root layout), nullptr for none.
// Returns false when a joint-space term D_i is not positive (degenerate model or NaN).
template <class S, int MB, int MD>
inline bool aba_solve(const Model<S, MB, MD>& m, Data<S, MB, MD>& d, const typename Model<S, MB, MD>::VecV& tau,
                     typename Model<S, MB, MD>::VecV& qdd, S h_damp, bool include_kd = true,
                     const Vec6<S>* root_damping = nullptr) {
  bool ok = true;
  for (int i = 0; i < m.nb; ++i) {
    d.IA[i] = m.bodies[i].I;
    d.pA[i] = d.bias[i];
    if (d.has_ext) {  // linearly implicit external load f = fext - Kext a  =>  I^A += Kext, p^A -= fext
      d.IA[i] += d.Kext[i];
      d.pA[i] -= d.fext[i];
    }
  }
  for (int i = m.nb - 1; i >= 0; --i) {
    const Body<S>& b = m.bodies[i];
    const S kdamp = h_damp * ((include_kd ? b.kd : S(0)) + b.damping);
    const Mat6<S>& IA = d.IA[i];
    const Vec6<S>& pA = d.pA[i];
    Mat6<S> Ia;   // I^a_i, articulated inertia passed to the parent
    Vec6<S> pa;   // p^a_i
    switch (b.joint) {
      case JointType::Free: {  // root only (validated): solved in pass 3
        if (root_damping) {
          Mat6<S> D = IA;
          for (int r = 0; r < 6; ++r) D(r, r) += h_damp * (*root_damping)(r);
          if (!cholesky_factor6(D, d.root_L)) ok = false;
        } else if (!cholesky_factor6(IA, d.root_L)) {
          ok = false;
        }
        d.u[i].setZero();
        continue;
      }
      case JointType::Spherical: {
        // S = [I3; 0]: U = I^A S is the first three columns of I^A (read in place, also in pass 3:
        // I^A_i is final once body i is reached), D the top-left 3x3 block.
        Mat3<S> D;
        SPARSEBODY_UNROLL for (int c = 0; c < 3; ++c)
          SPARSEBODY_UNROLL for (int r = 0; r < 3; ++r) D(r, c) = IA(r, c);
        D(0, 0) += kdamp; D(1, 1) += kdamp; D(2, 2) += kdamp;
        const Mat3<S> Dinv = inverse_sym3(D);
        d.Dinv[i] = Dinv;
        if (!(D(0, 0) > S(0)) || !Dinv.allFinite()) ok = false;
        const int k = b.v_index;
        const S u0 = tau(k) - pA(0), u1 = tau(k + 1) - pA(1), u2 = tau(k + 2) - pA(2);
        d.u[i] = Vec3<S>(u0, u1, u2);
        if (b.parent < 0) continue;
        // I^a = I^A - U D^-1 U^T, symmetric: lower triangle, mirrored; p^a = p^A + I^a c + U D^-1 u.
        S UD[6][3];
        SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r)
          SPARSEBODY_UNROLL for (int c = 0; c < 3; ++c)
            UD[r][c] = IA(r, 0) * Dinv(0, c) + IA(r, 1) * Dinv(1, c) + IA(r, 2) * Dinv(2, c);
        SPARSEBODY_UNROLL for (int c = 0; c < 6; ++c)
          SPARSEBODY_UNROLL for (int r = c; r < 6; ++r) {
            const S v = IA(r, c) - (UD[r][0] * IA(c, 0) + UD[r][1] * IA(c, 1) + UD[r][2] * IA(c, 2));
            Ia(r, c) = v;
            Ia(c, r) = v;
          }
        const Vec6<S> Iac = mul6v(Ia, d.c[i]);
        SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r)
          pa(r) = pA(r) + Iac(r) + (UD[r][0] * u0 + UD[r][1] * u1 + UD[r][2] * u2);
        break;
      }
      case JointType::Revolute: {
        const S ax = b.axis.x(), ay = b.axis.y(), az = b.axis.z();
        S Uc[6];
        for (int r = 0; r < 6; ++r) Uc[r] = IA(r, 0) * ax + IA(r, 1) * ay + IA(r, 2) * az;
        const S D = ax * Uc[0] + ay * Uc[1] + az * Uc[2] + kdamp;
        if (!(D > S(0))) ok = false;
        const S Dinv = S(1) / D;
        for (int r = 0; r < 6; ++r) d.U[i](r, 0) = Uc[r];
        d.Dinv[i](0, 0) = Dinv;
        const S u = tau(b.v_index) - (ax * pA(0) + ay * pA(1) + az * pA(2));
        d.u[i](0) = u;
        if (b.parent < 0) continue;
        S UD[6];
        for (int r = 0; r < 6; ++r) UD[r] = Uc[r] * Dinv;
        SPARSEBODY_UNROLL for (int c = 0; c < 6; ++c)
          SPARSEBODY_UNROLL for (int r = c; r < 6; ++r) {
            const S v = IA(r, c) - UD[r] * Uc[c];
            Ia(r, c) = v;
            Ia(c, r) = v;
          }
        const Vec6<S> Iac = mul6v(Ia, d.c[i]);
        for (int r = 0; r < 6; ++r) pa(r) = pA(r) + Iac(r) + UD[r] * u;
        break;
      }
      case JointType::Fixed:
      default:
        if (b.parent < 0) continue;
        Ia = IA;
        pa = pA + mul6v(IA, d.c[i]);
        break;
    }
    add_transformed_inertia(d.X[i], Ia, d.IA[b.parent]);        // I^A_lambda += X^T I^a X
    d.pA[b.parent] += d.X[i].apply_transpose_force(pa);          // p^A_lambda += X^T p^a
  }
  Vec6<S> a0 = Vec6<S>::Zero();
  a0.template tail<3>() = -m.gravity;
  qdd.resize(m.nv);
  for (int i = 0; i < m.nb; ++i) {
    const Body<S>& b = m.bodies[i];
    Vec6<S> ap = d.X[i].apply(b.parent < 0 ? a0 : d.a[b.parent]);  // a'_i = X a_lambda + c_i
    for (int r = 0; r < 6; ++r) ap(r) += d.c[i](r);
    const int k = b.v_index;
    switch (b.joint) {
      case JointType::Free: {  // S = I: qdd = (I^A + h K_r)^-1 (tau - p^A + h K_r a') - a'
        Vec6<S> x;
        for (int r = 0; r < 6; ++r) x(r) = tau(k + r) - d.pA[i](r);
        if (root_damping)
          for (int r = 0; r < 6; ++r) x(r) += h_damp * (*root_damping)(r) * ap(r);
        cholesky_solve6(d.root_L, x);
        for (int r = 0; r < 6; ++r) qdd(k + r) = x(r) - ap(r);
        d.a[i] = x;
        break;
      }
      case JointType::Spherical: {
        const Mat6<S>& U = d.IA[i];  // U = I^A S = first three columns
        const Mat3<S>& Dinv = d.Dinv[i];
        S y[3];
        for (int c = 0; c < 3; ++c)
          y[c] = d.u[i](c) - (U(0, c) * ap(0) + U(1, c) * ap(1) + U(2, c) * ap(2) + U(3, c) * ap(3) +
                              U(4, c) * ap(4) + U(5, c) * ap(5));
        for (int r = 0; r < 3; ++r) {
          const S x = Dinv(r, 0) * y[0] + Dinv(r, 1) * y[1] + Dinv(r, 2) * y[2];
          qdd(k + r) = x;
          ap(r) += x;
        }
        d.a[i] = ap;
        break;
      }
      case JointType::Revolute: {
        const Mat63<S>& U = d.U[i];
        const S x = d.Dinv[i](0, 0) * (d.u[i](0) - (U(0, 0) * ap(0) + U(1, 0) * ap(1) + U(2, 0) * ap(2) +
                                                    U(3, 0) * ap(3) + U(4, 0) * ap(4) + U(5, 0) * ap(5)));
        qdd(k) = x;
        ap(0) += b.axis.x() * x;
        ap(1) += b.axis.y() * x;
        ap(2) += b.axis.z() * x;
        d.a[i] = ap;
        break;
      }
      case JointType::Fixed:
      default: d.a[i] = ap; break;
    }
  }
  return ok;
}

// Forward dynamics qdd = (M + h Kd)^-1 (tau - C(q, qd) + J^T f_ext) (Kd with K_r on the root DoFs).
template <class S, int MB, int MD>
inline bool aba(const Model<S, MB, MD>& m, Data<S, MB, MD>& d, const typename Model<S, MB, MD>::VecQ& q,
                const typename Model<S, MB, MD>::VecV& qd, const typename Model<S, MB, MD>::VecV& tau,
                typename Model<S, MB, MD>::VecV& qdd, S h_damp = S(0), bool include_kd = true,
                const Vec6<S>* root_damping = nullptr) {
  aba_kinematics(m, d, q, qd);
  return aba_solve(m, d, tau, qdd, h_damp, include_kd, root_damping);
}

}  // namespace sparsebody::dynamics
