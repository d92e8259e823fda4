// Composite-rigid-body algorithm (Featherstone Table 6.2): joint-space inertia matrix M(q).
// O(n d) and dense output, so the step never uses it; it is the independent oracle for ABA.
#pragma once
#include "sparsebody/dynamics/kinematics.hpp"

namespace sparsebody::dynamics {

template <class S, int MB, int MD>
inline void crba(const Model<S, MB, MD>& m, Data<S, MB, MD>& d, const typename Model<S, MB, MD>::VecQ& q) {
  forward_kinematics(m, d, q, nullptr, false);
  for (int i = 0; i < m.nb; ++i) d.Ic[i] = m.bodies[i].I;
  for (int i = m.nb - 1; i >= 0; --i) {
    const int pi = m.bodies[i].parent;
    if (pi >= 0) add_transformed_inertia(d.X[i], d.Ic[i], d.Ic[pi]);  // I^c_lambda += X^T I^c_i X
  }
  d.Mass.setZero(m.nv, m.nv);
  using F6 = Eigen::Matrix<S, 6, Eigen::Dynamic, 0, 6, 6>;
  for (int i = 0; i < m.nb; ++i) {
    const Body<S>& b = m.bodies[i];
    const int ni = joint_nv(b.joint);
    if (ni == 0) continue;
    F6 F(6, ni);  // F = I^c_i S_i
    switch (b.joint) {
      case JointType::Free: F = d.Ic[i]; break;
      case JointType::Spherical: F = d.Ic[i].template leftCols<3>(); break;
      default: F = d.Ic[i].template leftCols<3>() * b.axis; break;
    }
    // Column block j of row i: S_j^T F, walking F up the tree with X^T.
    for (int j = i;;) {
      const Body<S>& bj = m.bodies[j];
      const int nj = joint_nv(bj.joint);
      if (nj > 0) {
        Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6> blk(nj, ni);
        switch (bj.joint) {
          case JointType::Free: blk = F; break;
          case JointType::Spherical: blk = F.template topRows<3>(); break;
          default: blk = bj.axis.transpose() * F.template topRows<3>(); break;
        }
        d.Mass.block(bj.v_index, b.v_index, nj, ni) = blk;
        d.Mass.block(b.v_index, bj.v_index, ni, nj) = blk.transpose();
      }
      const int pj = bj.parent;
      if (pj < 0) break;
      for (int k = 0; k < ni; ++k) F.col(k) = d.X[j].apply_transpose_force(Vec6<S>(F.col(k)));
      j = pj;
    }
  }
}

}  // namespace sparsebody::dynamics
