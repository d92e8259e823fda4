// Composite-rigid-body algorithm, Featherstone (2008) Table 6.2: the joint-space inertia matrix
// H = M(q), in his symbols (body i, parent lambda(i), motion subspace S_i, body coordinates):
//   I^c_i = I_i + sum over children j of X_j^T I^c_j X_j                      (leaves to root)
//   F = I^c_i S_i,  H_ii = S_i^T F;  then for each ancestor j of i, walking up: F = X^T F, H_ji = S_j^T F
// Dense O(n d) output, so the step never uses it; it is the independent oracle for ABA.
#pragma once
#include <array>

#include "sparsebody/dynamics/kinematics.hpp"

namespace sparsebody::dynamics {

// CRBA's output, kept out of the per-step Data (a MaxDofs^2 matrix that only tests and oracles read).
template <class S, int MB, int MD>
struct CrbaData {
  using ModelT = Model<S, MB, MD>;
  typename ModelT::MatV M;          // H = M(q), nv x nv; fixed storage, no heap
  std::array<Mat6<S>, MB> Ic{};     // I^c_i, composite inertia of the subtree rooted at body i

  CrbaData() = default;
  explicit CrbaData(const ModelT& m) { resize(m); }
  // H's entries between bodies on different branches are structurally zero: set here, never written
  // by crba() (which, like RBDL's, writes only the blocks of ancestor pairs).
  void resize(const ModelT& m) { M.setZero(m.nv, m.nv); }
};

namespace detail {

// Block H_ji = S_j^T F for an ancestor j (or j = i) of body i, F = the N columns of X^T I^c_i S_i
// expressed in body j; written at rows v_j, columns v_i and mirrored. The diagonal block is
// symmetrised from its lower triangle, so H is exactly symmetric.
template <int N, class S, class MatV>
SPARSEBODY_INLINE void crba_write_block(const Body<S>& bj, int vi, bool diagonal, const std::array<Vec6<S>, N>& F, MatV& H) {
  const int vj = bj.v_index;
  auto put = [&](int r, int c, S x) {  // H(vj + r, vi + c)
    if (diagonal && r < c) return;
    H(vj + r, vi + c) = x;
    H(vi + c, vj + r) = x;
  };
  switch (bj.joint) {
    case JointType::Free:  // S = 1_6
      for (int c = 0; c < N; ++c)
        for (int r = 0; r < 6; ++r) put(r, c, F[c](r));
      break;
    case JointType::Spherical:  // S = [1_3; 0]
      for (int c = 0; c < N; ++c)
        for (int r = 0; r < 3; ++r) put(r, c, F[c](r));
      break;
    case JointType::Revolute: {  // S = [axis; 0]
      const S ax = bj.axis.x(), ay = bj.axis.y(), az = bj.axis.z();
      for (int c = 0; c < N; ++c) put(0, c, ax * F[c](0) + ay * F[c](1) + az * F[c](2));
      break;
    }
    case JointType::Fixed: break;
  }
}

// Column block i of H (and its mirror row): F = I^c_i S_i carried up the tree by X^T.
template <int N, class S, int MB, int MD>
inline void crba_columns(const Model<S, MB, MD>& m, const Data<S, MB, MD>& d, int i, const std::array<Vec6<S>, N>& F0,
                         typename Model<S, MB, MD>::MatV& H) {
  std::array<Vec6<S>, N> F = F0;
  const int vi = m.bodies[i].v_index;
  for (int j = i;;) {
    const Body<S>& bj = m.bodies[j];
    crba_write_block<N>(bj, vi, j == i, F, H);
    if (bj.parent < 0) break;
    for (int c = 0; c < N; ++c) F[c] = d.X[j].apply_transpose_force(F[c]);  // to the parent's coordinates
    j = bj.parent;
  }
}

}  // namespace detail

// I^c_i for every body, leaves to root (after forward kinematics: needs X_i).
template <class S, int MB, int MD>
inline void composite_inertias(const Model<S, MB, MD>& m, const Data<S, MB, MD>& d, CrbaData<S, MB, MD>& out) {
  for (int i = 0; i < m.nb; ++i) out.Ic[i] = m.bodies[i].I;
  for (int i = m.nb - 1; i >= 0; --i) {
    const int pi = m.bodies[i].parent;
    if (pi >= 0) add_transformed_inertia(d.X[i], out.Ic[i], out.Ic[pi]);  // I^c_lambda += X^T I^c_i X
  }
}

// H = M(q) into out.M (d: positions-only forward kinematics are written into it), each joint's
// armature (Body::armature) on its diagonal.
template <class S, int MB, int MD>
inline void crba(const Model<S, MB, MD>& m, Data<S, MB, MD>& d, const typename Model<S, MB, MD>::VecQ& q,
                 CrbaData<S, MB, MD>& out) {
  forward_kinematics(m, d, q, nullptr, false);
  if (out.M.rows() != m.nv || out.M.cols() != m.nv) out.resize(m);
  composite_inertias(m, d, out);
  for (int i = 0; i < m.nb; ++i) {
    const Body<S>& b = m.bodies[i];
    const Mat6<S>& Ic = out.Ic[i];
    switch (b.joint) {
      case JointType::Free: {  // F = I^c
        std::array<Vec6<S>, 6> F;
        for (int c = 0; c < 6; ++c) F[c] = Ic.col(c);
        detail::crba_columns<6>(m, d, i, F, out.M);
        break;
      }
      case JointType::Spherical: {  // F = first three columns of I^c
        std::array<Vec6<S>, 3> F;
        for (int c = 0; c < 3; ++c) F[c] = Ic.col(c);
        detail::crba_columns<3>(m, d, i, F, out.M);
        break;
      }
      case JointType::Revolute: {  // F = I^c [axis; 0]
        std::array<Vec6<S>, 1> F;
        const S ax = b.axis.x(), ay = b.axis.y(), az = b.axis.z();
        for (int r = 0; r < 6; ++r) F[0](r) = Ic(r, 0) * ax + Ic(r, 1) * ay + Ic(r, 2) * az;
        detail::crba_columns<1>(m, d, i, F, out.M);
        break;
      }
      case JointType::Fixed: break;
    }
    // Armature: rotor inertia on the joint's own diagonal (the free root has none).
    if (b.joint != JointType::Free)
      for (int r = 0; r < joint_nv(b.joint); ++r) out.M(b.v_index + r, b.v_index + r) += b.armature;
  }
}

}  // namespace sparsebody::dynamics
