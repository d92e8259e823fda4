// Articulated-body algorithm, Featherstone, "Rigid Body Dynamics Algorithms" (2008), Table 7.1,
// in his symbols (body i, parent lambda(i), motion subspace S_i, all in body coordinates):
//   pass 1, root to leaves:  v_i = X_i v_lambda + S_i qd_i,  c_i = v_i x S_i qd_i,  p^A_i = v_i x* I_i v_i
//   pass 2, leaves to root:  U_i = I^A_i S_i,  D_i = S_i^T U_i,  u_i = tau_i - S_i^T p^A_i,
//                            I^a_i = I^A_i - U_i D_i^-1 U_i^T,  p^a_i = p^A_i + I^a_i c_i + U_i D_i^-1 u_i,
//                            I^A_lambda += X_i^T I^a_i X_i,  p^A_lambda += X_i^T p^a_i
//   pass 3, root to leaves:  a'_i = X_i a_lambda + c_i,  qdd_i = D_i^-1 (u_i - U_i^T a'_i),  a_i = a'_i + S_i qdd_i
// with gravity as the base acceleration a_0 = -g.
//
// Implicit diagonal: Data::implicit_diagonal (one entry per DoF) is added to D_i, the way
// Pinocchio adds a joint's armature. The simulator puts h (kd + damping) there, which makes the
// damping torque -Kd (qd + h qdd) implicit: the result is exactly (M + h Kd)^-1 (tau - C), because
// the same D_i enters I^a_i (the CRBA oracle test checks this). On the free root (S = 1_6, no
// parent) the 6 entries are added to I^A itself, D = I^A + diag(k), and its solve is written for
// a = a' + qdd: (I^A + diag(k)) a = tau - p^A + diag(k) a'.
//
// Armature (Body::armature, a joint's rotor inertia, MuJoCo's `armature`) is added to D_i the same
// way, so M includes it (as in CRBA and RNEA). It lets bounded torques drive light segments (a
// hand's twist, a toe) stably at a coarse time step.
//
// External loads (Data::fext, Data::Kext, filled by contact): f = f_ext - K_ext a enters pass 2 as
// I^A_i = I_i + K_ext_i and p^A_i = p_i - f_ext_i.
#pragma once
#include "sparsebody/dynamics/kinematics.hpp"

namespace sparsebody::dynamics {

// ---- pass 1 --------------------------------------------------------------------------------------

// p_i = v_i x* I_i v_i, the velocity-product force of each body (needs v_i from forward_kinematics).
template <class S, int MB, int MD>
inline void velocity_product_forces(const Model<S, MB, MD>& m, Data<S, MB, MD>& d) {
  for (int i = 0; i < m.nb; ++i) {
    S v[6], h[6], p[6];
    SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) v[r] = d.v[i](r);
    mul_rigid_inertia(m.bodies[i].I, v, h);
    cross_force(v, h, p);
    Vec6<S>& bias = d.bias[i];
    SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) bias(r) = p[r];
  }
}

// X_i, v_i, c_i (forward_kinematics; world poses only when asked) and p_i.
template <class S, int MB, int MD>
inline void aba_forward_pass(const Model<S, MB, MD>& m, Data<S, MB, MD>& d, const typename Model<S, MB, MD>::VecQ& q,
                             const typename Model<S, MB, MD>::VecV& qd, bool with_world = false) {
  forward_kinematics(m, d, q, &qd, with_world);
  velocity_product_forces(m, d);
}

// ---- pass 2, one function per joint type -----------------------------------------------------------
// (SPARSEBODY_INLINE: the per-joint functions are parts of one loop body, not calls.) Each writes U_i, D_i^-1, u_i into d and, when body i has a parent, I^a_i and p^a_i. False when
// D_i is not positive (degenerate model or NaN).

// Free root, S = 1_6: U = I^A, D = I^A + diag(k). Only its Cholesky factor is kept (pass 3 solves
// with it); a free joint has no parent (Model validates this).
template <class S, int MB, int MD>
SPARSEBODY_INLINE bool free_root_articulated(const Body<S>& b, int i, Data<S, MB, MD>& d) {
  Mat6<S> D = d.IA[i];
  for (int r = 0; r < 6; ++r) D(r, r) += d.implicit_diagonal(b.v_index + r);
  d.u[i].setZero();
  return cholesky_factor6(D, d.root_L, d.root_L_inv_diag);
}

// Spherical, S = [1_3; 0]: U = I^A S is the first three columns of I^A (read in place, in pass 3
// too: I^A_i is final once body i is reached), D the top-left 3x3 block of I^A plus K = diag(k).
// With A that block, U = [A; B^T] and D = A + K, the Schur complement I^a = I^A - U D^-1 U^T is
// computed as
//   I^a_AA = K - K D^-1 K,  I^a_AB = K G,  I^a_BB = C - B^T G,  G = D^-1 B,
// (A D^-1 = 1 - K D^-1), and U D^-1 u = [u - K z; G^T u], z = D^-1 u: 40 % fewer products than
// forming U D^-1, and no cancellation in I^a_AA (A - A D^-1 A is the difference of two near-equal
// matrices when K is small).
template <class S, int MB, int MD>
SPARSEBODY_INLINE bool spherical_articulated(const Body<S>& b, int i, Data<S, MB, MD>& d, const typename Model<S, MB, MD>::VecV& tau,
                                  Mat6<S>& Ia, Vec6<S>& pa) {
  const Mat6<S>& IA = d.IA[i];  // lower triangle (aba_backward_pass)
  const Vec6<S>& pA = d.pA[i];
  const int k = b.v_index;
  const S kk[3] = {d.implicit_diagonal(k) + b.armature, d.implicit_diagonal(k + 1) + b.armature,
                   d.implicit_diagonal(k + 2) + b.armature};
  const S d00 = IA(0, 0) + kk[0];
  S Di[3][3];  // D^-1
  const S inv = inverse_sym3(d00, IA(1, 0), IA(2, 0), IA(1, 1) + kk[1], IA(2, 1), IA(2, 2) + kk[2], Di);
  Mat3<S>& Dinv = d.Dinv[i];
  SPARSEBODY_UNROLL for (int c = 0; c < 3; ++c)
    SPARSEBODY_UNROLL for (int r = 0; r < 3; ++r) Dinv(r, c) = Di[r][c];
  const bool ok = d00 > S(0) && std::isfinite(inv) && inv > S(0);  // a positive pivot and determinant
  const S u[3] = {tau(k) - pA(0), tau(k + 1) - pA(1), tau(k + 2) - pA(2)};  // u = tau - S^T p^A
  d.u[i] = Vec3<S>(u[0], u[1], u[2]);
  if (b.parent < 0) return ok;
  S G[3][3];  // D^-1 B, B(r, c) = I^A(r, 3 + c) = IA(3 + c, r)
  SPARSEBODY_UNROLL for (int c = 0; c < 3; ++c)
    SPARSEBODY_UNROLL for (int r = 0; r < 3; ++r) G[r][c] = Di[r][0] * IA(3 + c, 0) + Di[r][1] * IA(3 + c, 1) + Di[r][2] * IA(3 + c, 2);
  // I^a, lower triangle only (add_transformed_inertia_lower reads no more)
  SPARSEBODY_UNROLL for (int c = 0; c < 3; ++c) {
    SPARSEBODY_UNROLL for (int r = 0; r < 3; ++r) {
      if (r >= c) {
        Ia(r, c) = (r == c ? kk[r] : S(0)) - kk[r] * kk[c] * Di[r][c];
        Ia(3 + r, 3 + c) = sym_lower(IA, 3 + r, 3 + c) - (IA(3 + r, 0) * G[0][c] + IA(3 + r, 1) * G[1][c] + IA(3 + r, 2) * G[2][c]);
      }
      Ia(3 + c, r) = kk[r] * G[r][c];  // (K G)(r, c), stored transposed below the diagonal
    }
  }
  // p^a = p^A + I^a c + U D^-1 u
  const S z[3] = {Di[0][0] * u[0] + Di[0][1] * u[1] + Di[0][2] * u[2], Di[1][0] * u[0] + Di[1][1] * u[1] + Di[1][2] * u[2],
                  Di[2][0] * u[0] + Di[2][1] * u[1] + Di[2][2] * u[2]};
  const Vec6<S> Iac = mul6v_lower(Ia, d.c[i]);
  SPARSEBODY_UNROLL for (int r = 0; r < 3; ++r) {
    pa(r) = pA(r) + Iac(r) + (u[r] - kk[r] * z[r]);
    pa(3 + r) = pA(3 + r) + Iac(3 + r) + (G[0][r] * u[0] + G[1][r] * u[1] + G[2][r] * u[2]);
  }
  return ok;
}

// Revolute, S = [axis; 0]: U = I^A S (stored, column 0 of d.U), D = S^T U + k, a scalar.
template <class S, int MB, int MD>
SPARSEBODY_INLINE bool revolute_articulated(const Body<S>& b, int i, Data<S, MB, MD>& d, const typename Model<S, MB, MD>::VecV& tau,
                                 Mat6<S>& Ia, Vec6<S>& pa) {
  const Mat6<S>& IA = d.IA[i];  // lower triangle (aba_backward_pass)
  const Vec6<S>& pA = d.pA[i];
  const S ax = b.axis.x(), ay = b.axis.y(), az = b.axis.z();
  S Uc[6];
  SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r)
    Uc[r] = sym_lower(IA, r, 0) * ax + sym_lower(IA, r, 1) * ay + sym_lower(IA, r, 2) * az;
  const S D = ax * Uc[0] + ay * Uc[1] + az * Uc[2] + d.implicit_diagonal(b.v_index) + b.armature;
  const bool ok = D > S(0);
  const S Dinv = S(1) / D;
  SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) d.U[i](r, 0) = Uc[r];
  d.Dinv[i](0, 0) = Dinv;
  const S u = tau(b.v_index) - (ax * pA(0) + ay * pA(1) + az * pA(2));
  d.u[i](0) = u;
  if (b.parent < 0) return ok;
  S UD[6];  // U D^-1
  SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) UD[r] = Uc[r] * Dinv;
  SPARSEBODY_UNROLL for (int c = 0; c < 6; ++c)  // I^a = I^A - U D^-1 U^T, lower triangle
    SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r)
      if (r >= c) Ia(r, c) = IA(r, c) - UD[r] * Uc[c];
  const Vec6<S> Iac = mul6v_lower(Ia, d.c[i]);
  SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) pa(r) = pA(r) + Iac(r) + UD[r] * u;
  return ok;
}

// Fixed, S empty: I^a = I^A, p^a = p^A + I^A c.
template <class S, int MB, int MD>
SPARSEBODY_INLINE void fixed_articulated(int i, const Data<S, MB, MD>& d, Mat6<S>& Ia, Vec6<S>& pa) {
  Ia = d.IA[i];
  pa = d.pA[i] + mul6v_lower(d.IA[i], d.c[i]);
}

// Pass 2: I^A_i and p^A_i from the leaves to the root, after pass 1 (p_i in d.bias). I^A and I^a
// are symmetric and kept in their lower triangles only (add_transformed_inertia_lower): the upper
// triangles of d.IA are not updated and must not be read.
template <class S, int MB, int MD>
inline bool aba_backward_pass(const Model<S, MB, MD>& m, Data<S, MB, MD>& d, const typename Model<S, MB, MD>::VecV& tau) {
  for (int i = 0; i < m.nb; ++i) {
    d.IA[i] = m.bodies[i].I;
    d.pA[i] = d.bias[i];
    if (d.has_ext) {  // f = f_ext - K_ext a  =>  I^A += K_ext, p^A -= f_ext
      d.IA[i] += d.Kext[i];
      d.pA[i] -= d.fext[i];
    }
  }
  bool ok = true;
  for (int i = m.nb - 1; i >= 0; --i) {
    const Body<S>& b = m.bodies[i];
    Mat6<S> Ia;  // I^a_i, passed to the parent
    Vec6<S> pa;  // p^a_i
    switch (b.joint) {
      case JointType::Free: ok = free_root_articulated(b, i, d) && ok; continue;
      case JointType::Spherical: ok = spherical_articulated(b, i, d, tau, Ia, pa) && ok; break;
      case JointType::Revolute: ok = revolute_articulated(b, i, d, tau, Ia, pa) && ok; break;
      case JointType::Fixed:
      default:
        if (b.parent >= 0) fixed_articulated(i, d, Ia, pa);
        break;
    }
    if (b.parent < 0) continue;
    add_transformed_inertia_lower(d.X[i], Ia, d.IA[b.parent]);  // I^A_lambda += X^T I^a X
    S o[6];  // p^A_lambda += X^T p^a
    d.X[i].apply_transpose_force(pa.data(), o);
    Vec6<S>& pA = d.pA[b.parent];
    SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) pA(r) += o[r];
  }
  return ok;
}

// ---- pass 3, one function per joint type -----------------------------------------------------------
// Each takes a'_i in ap[6], writes qdd_i and leaves a_i in ap. The spatial vectors of this pass are
// plain scalars: built in an Eigen Vec6 on the stack by scalar stores and read back by packed
// loads, they stalled on store forwarding (27 % of the pass).

// Free root: a = (I^A + diag(k))^-1 (tau - p^A + diag(k) a'), qdd = a - a'.
template <class S, int MB, int MD>
SPARSEBODY_INLINE void free_root_acceleration(const Body<S>& b, int i, Data<S, MB, MD>& d, const typename Model<S, MB, MD>::VecV& tau,
                                   S* ap, typename Model<S, MB, MD>::VecV& qdd) {
  const int k = b.v_index;
  Vec6<S> x;
  SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) x(r) = tau(k + r) - d.pA[i](r) + d.implicit_diagonal(k + r) * ap[r];
  cholesky_solve6(d.root_L, d.root_L_inv_diag, x);
  SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) {
    qdd(k + r) = x(r) - ap[r];
    ap[r] = x(r);
  }
}

// Spherical: qdd = D^-1 (u - U^T a') with U the first three columns of I^A; a = a' + [qdd; 0].
template <class S, int MB, int MD>
SPARSEBODY_INLINE void spherical_acceleration(const Body<S>& b, int i, const Data<S, MB, MD>& d, S* ap,
                                   typename Model<S, MB, MD>::VecV& qdd) {
  const Mat6<S>& U = d.IA[i];  // lower triangle
  const Mat3<S>& Dinv = d.Dinv[i];
  S y[3];  // u - U^T a'
  SPARSEBODY_UNROLL for (int c = 0; c < 3; ++c)
    y[c] = d.u[i](c) - ((sym_lower(U, 0, c) * ap[0] + sym_lower(U, 1, c) * ap[1]) + (sym_lower(U, 2, c) * ap[2] + U(3, c) * ap[3]) +
                        (U(4, c) * ap[4] + U(5, c) * ap[5]));
  SPARSEBODY_UNROLL for (int r = 0; r < 3; ++r) {
    const S x = Dinv(r, 0) * y[0] + Dinv(r, 1) * y[1] + Dinv(r, 2) * y[2];
    qdd(b.v_index + r) = x;
    ap[r] += x;
  }
}

// Revolute: qdd = D^-1 (u - U^T a'); a = a' + [axis qdd; 0].
template <class S, int MB, int MD>
SPARSEBODY_INLINE void revolute_acceleration(const Body<S>& b, int i, const Data<S, MB, MD>& d, S* ap,
                                  typename Model<S, MB, MD>::VecV& qdd) {
  const Mat63<S>& U = d.U[i];
  const S x = d.Dinv[i](0, 0) * (d.u[i](0) - ((U(0, 0) * ap[0] + U(1, 0) * ap[1]) + (U(2, 0) * ap[2] + U(3, 0) * ap[3]) +
                                              (U(4, 0) * ap[4] + U(5, 0) * ap[5])));
  qdd(b.v_index) = x;
  ap[0] += b.axis.x() * x;
  ap[1] += b.axis.y() * x;
  ap[2] += b.axis.z() * x;
}

// Pass 3: a_i and qdd from the root to the leaves, after pass 2.
template <class S, int MB, int MD>
inline void aba_acceleration_pass(const Model<S, MB, MD>& m, Data<S, MB, MD>& d, const typename Model<S, MB, MD>::VecV& tau,
                                  typename Model<S, MB, MD>::VecV& qdd) {
  qdd.resize(m.nv);
  for (int i = 0; i < m.nb; ++i) {
    const Body<S>& b = m.bodies[i];
    S in[6];  // a_lambda (a_0 = -g at the root)
    if (b.parent < 0) {
      in[0] = in[1] = in[2] = S(0);
      in[3] = -m.gravity.x();
      in[4] = -m.gravity.y();
      in[5] = -m.gravity.z();
    } else {
      const Vec6<S>& a = d.a[b.parent];
      SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) in[r] = a(r);
    }
    S ap[6];  // a'_i = X_i a_lambda + c_i
    d.X[i].apply(in, ap);
    SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) ap[r] += d.c[i](r);
    switch (b.joint) {
      case JointType::Free: free_root_acceleration(b, i, d, tau, ap, qdd); break;
      case JointType::Spherical: spherical_acceleration(b, i, d, ap, qdd); break;
      case JointType::Revolute: revolute_acceleration(b, i, d, ap, qdd); break;
      case JointType::Fixed:
      default: break;
    }
    Vec6<S>& a = d.a[i];
    SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) a(r) = ap[r];
  }
}

// ---- the algorithm --------------------------------------------------------------------------------

// Passes 2 and 3 on the kinematics and p_i already in d: what a contact solve repeats with new
// external loads. False when a D_i is not positive (degenerate model or NaN).
template <class S, int MB, int MD>
inline bool aba_solve(const Model<S, MB, MD>& m, Data<S, MB, MD>& d, const typename Model<S, MB, MD>::VecV& tau,
                      typename Model<S, MB, MD>::VecV& qdd) {
  const bool ok = aba_backward_pass(m, d, tau);
  aba_acceleration_pass(m, d, tau, qdd);
  return ok;
}

// Forward dynamics qdd = (M + diag(d.implicit_diagonal))^-1 (tau - C(q, qd) + J^T f_ext).
template <class S, int MB, int MD>
inline bool aba(const Model<S, MB, MD>& m, Data<S, MB, MD>& d, const typename Model<S, MB, MD>::VecQ& q,
                const typename Model<S, MB, MD>::VecV& qd, const typename Model<S, MB, MD>::VecV& tau,
                typename Model<S, MB, MD>::VecV& qdd) {
  aba_forward_pass(m, d, q, qd);
  return aba_solve(m, d, tau, qdd);
}

}  // namespace sparsebody::dynamics
