// Articulated-body algorithm (Featherstone Table 7.1) with implicit joint damping.
//
// Implicit damping: the servo/passive damping torque is evaluated at the next velocity,
// tau_d = -Kd (qd + h qdd), so the dynamics become (M + h Kd) qdd = tau - C with tau holding the
// explicit part (-Kd qd). Only ABA's joint-space term changes:
//   D_i = S_i^T I^A_i S_i + h Kd_i,   u_i = tau_i - S_i^T p^A_i,
// and the same D_i is used in the parent update I^a_i = I^A_i - U_i D_i^-1 U_i^T, so the result is
// exactly the (M + h Kd)^-1 solve (this is what the CRBA test checks). Kd_i = (kd_i + damping_i) I.
#pragma once
#include "kinematics.hpp"

namespace sparsebody::dynamics {

// Pass 1: kinematics plus the per-body velocity-product force v x* I v.
template <class S, int MB, int MD>
inline void abaKinematics(const Model<S, MB, MD>& m, Data<S, MB, MD>& d, const typename Model<S, MB, MD>::VecQ& q,
                          const typename Model<S, MB, MD>::VecV& qd, bool with_world = false) {
  forwardKinematics(m, d, q, &qd, with_world);
  for (int i = 0; i < m.nb; ++i) d.bias[i] = crossForce(d.v[i], mul6v(m.bodies[i].I, d.v[i]));
}

// Passes 2 and 3, after abaKinematics. h_damp = h for implicit damping, 0 for explicit.
// When include_kd is false only the passive damping is implicit (torque-driven use).
// Returns false when a joint-space term D_i is not positive (degenerate model or NaN).
template <class S, int MB, int MD>
inline bool abaSolve(const Model<S, MB, MD>& m, Data<S, MB, MD>& d, const typename Model<S, MB, MD>::VecV& tau,
                     typename Model<S, MB, MD>::VecV& qdd, S h_damp, bool include_kd = true) {
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
    Mat6<S>& IA = d.IA[i];
    Mat6<S> Ia;   // I^a_i, articulated inertia passed to the parent
    Vec6<S> pa;   // p^a_i
    switch (b.joint) {
      case JointType::Free: {  // root only (validated): solved in pass 3
        d.root_llt.compute(IA);
        if (d.root_llt.info() != Eigen::Success) ok = false;
        d.u[i].setZero();
        continue;
      }
      case JointType::Spherical: {
        // S = [I3; 0]: U = I^A S is the first three columns, D the top-left 3x3 block.
        d.U[i] = IA.template leftCols<3>();
        Mat3<S> D = IA.template topLeftCorner<3, 3>();
        D.diagonal().array() += kdamp;
        d.Dinv[i] = inverseSym3(D);
        if (!(D(0, 0) > S(0)) || !d.Dinv[i].allFinite()) ok = false;
        d.u[i] = tau.template segment<3>(b.v_index) - d.pA[i].template head<3>();
        if (b.parent < 0) continue;
        // I^a = I^A - U D^-1 U^T, symmetric: lower triangle by loops, then mirrored.
        const Mat63<S>& U = d.U[i];
        Mat63<S> UD;
        for (int c = 0; c < 3; ++c)
          for (int r = 0; r < 6; ++r)
            UD(r, c) = U(r, 0) * d.Dinv[i](0, c) + U(r, 1) * d.Dinv[i](1, c) + U(r, 2) * d.Dinv[i](2, c);
        for (int c = 0; c < 6; ++c)
          for (int r = c; r < 6; ++r) {
            const S v = IA(r, c) - (UD(r, 0) * U(c, 0) + UD(r, 1) * U(c, 1) + UD(r, 2) * U(c, 2));
            Ia(r, c) = v;
            Ia(c, r) = v;
          }
        pa = d.pA[i] + mul6v(Ia, d.c[i]) + UD * d.u[i];
        break;
      }
      case JointType::Revolute: {
        const Vec6<S> Ucol = IA.template leftCols<3>() * b.axis;
        const S D = b.axis.dot(Ucol.template head<3>()) + kdamp;
        if (!(D > S(0))) ok = false;
        d.U[i].col(0) = Ucol;
        d.Dinv[i](0, 0) = S(1) / D;
        d.u[i](0) = tau(b.v_index) - b.axis.dot(d.pA[i].template head<3>());
        if (b.parent < 0) continue;
        Ia = IA - (Ucol * d.Dinv[i](0, 0)) * Ucol.transpose();
        pa = d.pA[i] + mul6v(Ia, d.c[i]) + Ucol * (d.Dinv[i](0, 0) * d.u[i](0));
        break;
      }
      case JointType::Fixed:
      default:
        if (b.parent < 0) continue;
        Ia = IA;
        pa = d.pA[i] + mul6v(IA, d.c[i]);
        break;
    }
    addTransformedInertia(d.X[i], Ia, d.IA[b.parent]);        // I^A_lambda += X^T I^a X
    d.pA[b.parent] += d.X[i].applyTransposeForce(pa);          // p^A_lambda += X^T p^a
  }
  Vec6<S> a0 = Vec6<S>::Zero();
  a0.template tail<3>() = -m.gravity;
  qdd.resize(m.nv);
  for (int i = 0; i < m.nb; ++i) {
    const Body<S>& b = m.bodies[i];
    const Vec6<S> ap = d.X[i].apply(b.parent < 0 ? a0 : d.a[b.parent]) + d.c[i];  // a'_i
    switch (b.joint) {
      case JointType::Free: {  // S = I: qdd = (I^A)^-1 (tau - p^A) - a'
        const Vec6<S> rhs = tau.template segment<6>(b.v_index) - d.pA[i];
        const Vec6<S> acc = d.root_llt.solve(rhs);
        qdd.template segment<6>(b.v_index) = acc - ap;
        d.a[i] = acc;
        break;
      }
      case JointType::Spherical: {
        const Vec3<S> x = d.Dinv[i] * (d.u[i] - d.U[i].transpose() * ap);
        qdd.template segment<3>(b.v_index) = x;
        d.a[i] = ap;
        d.a[i].template head<3>() += x;
        break;
      }
      case JointType::Revolute: {
        const S x = d.Dinv[i](0, 0) * (d.u[i](0) - d.U[i].col(0).dot(ap));
        qdd(b.v_index) = x;
        d.a[i] = ap;
        d.a[i].template head<3>() += b.axis * x;
        break;
      }
      case JointType::Fixed:
      default: d.a[i] = ap; break;
    }
  }
  return ok;
}

// Forward dynamics qdd = (M + h Kd)^-1 (tau - C(q, qd) + J^T f_ext).
template <class S, int MB, int MD>
inline bool aba(const Model<S, MB, MD>& m, Data<S, MB, MD>& d, const typename Model<S, MB, MD>::VecQ& q,
                const typename Model<S, MB, MD>::VecV& qd, const typename Model<S, MB, MD>::VecV& tau,
                typename Model<S, MB, MD>::VecV& qdd, S h_damp = S(0), bool include_kd = true) {
  abaKinematics(m, d, q, qd);
  return abaSolve(m, d, tau, qdd, h_damp, include_kd);
}

}  // namespace sparsebody::dynamics
