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
#include <array>
#include <type_traits>

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
// (SPARSEBODY_INLINE: the per-joint functions are parts of one loop body, not calls.) Pass 2 steps
// one body (N = 1, values S) or two at once (N = 2, values Lanes2<S>: lane k is body ids[k]; the
// steps are Model::backward_steps): two bodies with the same joint go through the same arithmetic,
// one per lane of an SSE2/NEON register, in the instructions of one. Each function writes U_i,
// D_i^-1, u_i into d and, when the body has a parent, I^a_i and p^a_i (lower triangle) into Ia, pa.
// False when a D_i is not positive (degenerate model or NaN).

// Free root, S = 1_6: U = I^A, D = I^A + diag(k). Only its Cholesky factor is kept (pass 3 solves
// with it); a free joint has no parent (Model validates this).
template <class S, int MB, int MD>
SPARSEBODY_INLINE bool free_root_articulated(const Body<S>& b, int i, Data<S, MB, MD>& d) {
  Mat6<S> D = d.IA[i];
  for (int r = 0; r < 6; ++r) D(r, r) += d.implicit_diagonal(b.v_index + r);
  d.u[i].setZero();
  return cholesky_factor6(D, d.root_L, d.root_L_inv_diag);
}

// p^a = p^A + I^a c + w, the part every joint type shares (w = U D^-1 u).
template <class S, int N, int MB, int MD>
SPARSEBODY_INLINE void articulated_bias(const Data<S, MB, MD>& d, const int (&ids)[N], const Lane<S, N> (&Ia)[6][6],
                                        const Lane<S, N> (&w)[6], Lane<S, N> (&pa)[6]) {
  using V = Lane<S, N>;
  V c[6];
  SPARSEBODY_UNROLL for (int t = 0; t < 6; ++t) c[t] = gather<S, N>([&](int k) { return d.c[ids[k]](t); });
  SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) {
    V s = gather<S, N>([&](int k) { return d.pA[ids[k]](r); }) + w[r];
    SPARSEBODY_UNROLL for (int t = 0; t <= r; ++t) s += Ia[r][t] * c[t];  // (two loops: one with both
    SPARSEBODY_UNROLL for (int t = r + 1; t < 6; ++t) s += Ia[t][r] * c[t];  // triangles tripped -Warray-bounds)
    pa[r] = s;
  }
}

// Spherical, S = [1_3; 0]: U = I^A S is the first three columns of I^A (read in place, in pass 3
// too: I^A_i is final once body i is reached), D the top-left 3x3 block of I^A plus K = diag(k).
// With A that block, U = [A; B^T] and D = A + K, the Schur complement I^a = I^A - U D^-1 U^T is
// computed as
//   I^a_AA = K - K D^-1 K,  I^a_AB = K G,  I^a_BB = C - B^T G,  G = D^-1 B,
// (A D^-1 = 1 - K D^-1), and U D^-1 u = [u - K z; G^T u], z = D^-1 u: 40 % fewer products than
// forming U D^-1, and no cancellation in I^a_AA (A - A D^-1 A is the difference of two near-equal
// matrices when K is small).
template <int N, class S, int MB, int MD>
SPARSEBODY_INLINE bool spherical_articulated(const Model<S, MB, MD>& m, const int (&ids)[N], Data<S, MB, MD>& d,
                                             const typename Model<S, MB, MD>::VecV& tau, Lane<S, N> (&Ia)[6][6],
                                             Lane<S, N> (&pa)[6]) {
  using V = Lane<S, N>;
  const auto IA = [&](int r, int c) { return gather<S, N>([&](int k) { return d.IA[ids[k]](r, c); }); };  // r >= c
  V kk[3], u[3];  // K; u = tau - S^T p^A
  SPARSEBODY_UNROLL for (int t = 0; t < 3; ++t) {
    kk[t] = gather<S, N>([&](int k) {
      const Body<S>& b = m.bodies[ids[k]];
      return d.implicit_diagonal(b.v_index + t) + b.armature;
    });
    u[t] = gather<S, N>([&](int k) { return tau(m.bodies[ids[k]].v_index + t) - d.pA[ids[k]](t); });
  }
  const V d00 = IA(0, 0) + kk[0];
  V Di[3][3];  // D^-1
  const V inv = inverse_sym3(d00, IA(1, 0), IA(2, 0), IA(1, 1) + kk[1], IA(2, 1), IA(2, 2) + kk[2], Di);
  bool ok = true;
  for (int k = 0; k < N; ++k) {
    const int i = ids[k];
    Mat3<S>& Dinv = d.Dinv[i];
    SPARSEBODY_UNROLL for (int c = 0; c < 3; ++c)
      SPARSEBODY_UNROLL for (int r = 0; r < 3; ++r) Dinv(r, c) = lane<N>(Di[r][c], k);
    const S p = lane<N>(d00, k), q = lane<N>(inv, k);
    ok = ok && p > S(0) && std::isfinite(q) && q > S(0);  // a positive pivot and determinant
    d.u[i] = Vec3<S>(lane<N>(u[0], k), lane<N>(u[1], k), lane<N>(u[2], k));
  }
  if (N == 1 && m.bodies[ids[0]].parent < 0) return ok;
  V G[3][3];  // D^-1 B, B(r, c) = I^A(r, 3 + c) = IA(3 + c, r)
  SPARSEBODY_UNROLL for (int c = 0; c < 3; ++c)
    SPARSEBODY_UNROLL for (int r = 0; r < 3; ++r) G[r][c] = Di[r][0] * IA(3 + c, 0) + Di[r][1] * IA(3 + c, 1) + Di[r][2] * IA(3 + c, 2);
  // I^a, lower triangle only (congruence_lower reads no more)
  SPARSEBODY_UNROLL for (int c = 0; c < 3; ++c) {
    SPARSEBODY_UNROLL for (int r = 0; r < 3; ++r) {
      if (r >= c) {
        Ia[r][c] = -(kk[r] * kk[c] * Di[r][c]);
        if (r == c) Ia[r][c] += kk[r];
        const V Crc = 3 + r >= 3 + c ? IA(3 + r, 3 + c) : IA(3 + c, 3 + r);
        Ia[3 + r][3 + c] = Crc - (IA(3 + r, 0) * G[0][c] + IA(3 + r, 1) * G[1][c] + IA(3 + r, 2) * G[2][c]);
      }
      Ia[3 + c][r] = kk[r] * G[r][c];  // (K G)(r, c), stored transposed below the diagonal
    }
  }
  // p^a = p^A + I^a c + U D^-1 u
  const V z[3] = {Di[0][0] * u[0] + Di[0][1] * u[1] + Di[0][2] * u[2], Di[1][0] * u[0] + Di[1][1] * u[1] + Di[1][2] * u[2],
                  Di[2][0] * u[0] + Di[2][1] * u[1] + Di[2][2] * u[2]};
  V w[6];
  SPARSEBODY_UNROLL for (int r = 0; r < 3; ++r) {
    w[r] = u[r] - kk[r] * z[r];
    w[3 + r] = G[0][r] * u[0] + G[1][r] * u[1] + G[2][r] * u[2];
  }
  articulated_bias<S, N>(d, ids, Ia, w, pa);
  return ok;
}

// Revolute, S = [axis; 0]: U = I^A S (stored, column 0 of d.U), D = S^T U + k, a scalar.
template <int N, class S, int MB, int MD>
SPARSEBODY_INLINE bool revolute_articulated(const Model<S, MB, MD>& m, const int (&ids)[N], Data<S, MB, MD>& d,
                                            const typename Model<S, MB, MD>::VecV& tau, Lane<S, N> (&Ia)[6][6],
                                            Lane<S, N> (&pa)[6]) {
  using V = Lane<S, N>;
  const auto IA = [&](int r, int c) {  // both triangles, from the lower one
    return gather<S, N>([&](int k) { return r >= c ? d.IA[ids[k]](r, c) : d.IA[ids[k]](c, r); });
  };
  const V ax = gather<S, N>([&](int k) { return m.bodies[ids[k]].axis.x(); });
  const V ay = gather<S, N>([&](int k) { return m.bodies[ids[k]].axis.y(); });
  const V az = gather<S, N>([&](int k) { return m.bodies[ids[k]].axis.z(); });
  V Uc[6];
  SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) Uc[r] = IA(r, 0) * ax + IA(r, 1) * ay + IA(r, 2) * az;
  const V D = ax * Uc[0] + ay * Uc[1] + az * Uc[2] + gather<S, N>([&](int k) {
                const Body<S>& b = m.bodies[ids[k]];
                return d.implicit_diagonal(b.v_index) + b.armature;
              });
  const V Dinv = 1 / D;
  const V u = gather<S, N>([&](int k) {
    const Body<S>& b = m.bodies[ids[k]];
    const Vec6<S>& pA = d.pA[ids[k]];
    return tau(b.v_index) - (b.axis.x() * pA(0) + b.axis.y() * pA(1) + b.axis.z() * pA(2));
  });
  bool ok = true;
  for (int k = 0; k < N; ++k) {
    const int i = ids[k];
    SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) d.U[i](r, 0) = lane<N>(Uc[r], k);
    d.Dinv[i](0, 0) = lane<N>(Dinv, k);
    d.u[i](0) = lane<N>(u, k);
    ok = ok && lane<N>(D, k) > S(0);
  }
  if (N == 1 && m.bodies[ids[0]].parent < 0) return ok;
  V UD[6];  // U D^-1
  SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) UD[r] = Uc[r] * Dinv;
  SPARSEBODY_UNROLL for (int c = 0; c < 6; ++c)  // I^a = I^A - U D^-1 U^T, lower triangle
    SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r)
      if (r >= c) Ia[r][c] = IA(r, c) - UD[r] * Uc[c];
  V w[6];
  SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) w[r] = UD[r] * u;
  articulated_bias<S, N>(d, ids, Ia, w, pa);
  return ok;
}

// I^A_lambda += X^T I^a X and p^A_lambda += X^T p^a for each lane's body.
template <class S, int N, int MB, int MD>
SPARSEBODY_INLINE void add_to_parents(const Model<S, MB, MD>& m, Data<S, MB, MD>& d, const int (&ids)[N],
                                      const Lane<S, N> (&Ia)[6][6], const Lane<S, N> (&pa)[6]) {
  using V = Lane<S, N>;
  congruence_lower<V>([&](int r, int c) { return gather<S, N>([&](int k) { return d.X[ids[k]].E(r, c); }); },
                      gather<S, N>([&](int k) { return d.X[ids[k]].r.x(); }),
                      gather<S, N>([&](int k) { return d.X[ids[k]].r.y(); }),
                      gather<S, N>([&](int k) { return d.X[ids[k]].r.z(); }), [&](int r, int c) { return Ia[r][c]; },
                      [&](int r, int c, V x) {
                        for (int k = 0; k < N; ++k) d.IA[m.bodies[ids[k]].parent](r, c) += lane<N>(x, k);
                      });
  for (int k = 0; k < N; ++k) {
    S f[6], o[6];
    SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) f[r] = lane<N>(pa[r], k);
    d.X[ids[k]].apply_transpose_force(f, o);
    Vec6<S>& pA = d.pA[m.bodies[ids[k]].parent];
    SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r) pA(r) += o[r];
  }
}

// One step of pass 2: body ids[0], or the pair (ids[0], ids[1]) with the same joint type.
template <int N, class S, int MB, int MD>
SPARSEBODY_INLINE bool articulated_step(const Model<S, MB, MD>& m, Data<S, MB, MD>& d, const typename Model<S, MB, MD>::VecV& tau,
                                        const int (&ids)[N]) {
  using V = Lane<S, N>;
  const Body<S>& b = m.bodies[ids[0]];
  V Ia[6][6], pa[6];  // I^a_i, p^a_i, passed to the parent
  bool ok = true;
  switch (b.joint) {
    case JointType::Free: return free_root_articulated(b, ids[0], d);
    case JointType::Spherical: ok = spherical_articulated<N>(m, ids, d, tau, Ia, pa); break;
    case JointType::Revolute: ok = revolute_articulated<N>(m, ids, d, tau, Ia, pa); break;
    case JointType::Fixed:
    default: {  // S empty: I^a = I^A, p^a = p^A + I^A c
      if (b.parent < 0) return true;
      SPARSEBODY_UNROLL for (int c = 0; c < 6; ++c)
        SPARSEBODY_UNROLL for (int r = 0; r < 6; ++r)
          if (r >= c) Ia[r][c] = gather<S, N>([&](int k) { return d.IA[ids[k]](r, c); });
      const V w[6] = {};
      articulated_bias<S, N>(d, ids, Ia, w, pa);
      break;
    }
  }
  if (b.parent >= 0) add_to_parents<S, N>(m, d, ids, Ia, pa);
  return ok;
}

// Pass 2: I^A_i and p^A_i from the leaves to the root, after pass 1 (p_i in d.bias), in the steps
// Model::finalize planned (two bodies at once where it could pair them). I^A and I^a are symmetric
// and kept in their lower triangles only (congruence_lower): the upper triangles of d.IA are not
// updated and must not be read.
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
  if (m.backward_steps_nb != m.nb) {  // no plan for this tree (bodies edited without finalize): one at a time
    for (int i = m.nb - 1; i >= 0; --i) ok = articulated_step<1>(m, d, tau, {i}) && ok;
    return ok;
  }
  for (int s = 0; s < m.num_backward_steps; ++s) {
    const std::array<int, 2>& st = m.backward_steps[s];
    if constexpr (Lanes2Of<S>::vector) {
      if (st[1] >= 0) {
        ok = articulated_step<2>(m, d, tau, {st[0], st[1]}) && ok;
        continue;
      }
    }
    ok = articulated_step<1>(m, d, tau, {st[0]}) && ok;
    if (st[1] >= 0) ok = articulated_step<1>(m, d, tau, {st[1]}) && ok;
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
