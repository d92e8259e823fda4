// Body and point Jacobians in world coordinates (after forward_kinematics). Column k of a body's
// Jacobian is the world-frame motion produced by unit velocity of DoF k of one of its ancestors.
#pragma once
#include "sparsebody/dynamics/kinematics.hpp"

namespace sparsebody::dynamics {

// 6 x nv spatial Jacobian of body i: rows (angular; linear velocity of the body origin), world frame.
// J may be any Eigen matrix with 6 rows and >= nv columns; untouched columns are zeroed.
template <class S, int MB, int MD, class Mat>
inline void body_jacobian(const Model<S, MB, MD>& m, const Data<S, MB, MD>& d, int i, const Vec3<S>& point_body,
                         Mat& J) {
  J.setZero();
  const Vec3<S> pw = point_position(d, i, point_body);
  for (int j = i; j >= 0; j = m.bodies[j].parent) {
    const Body<S>& b = m.bodies[j];
    const Mat3<S>& R = d.R[j];
    const Vec3<S> lever = pw - d.p[j];
    auto angular = [&](int col, const Vec3<S>& axis_body) {
      const Vec3<S> w = R * axis_body;
      J.template block<3, 1>(0, col) = w;
      J.template block<3, 1>(3, col) = w.cross(lever);
    };
    switch (b.joint) {
      case JointType::Free:
        for (int k = 0; k < 3; ++k) {
          angular(b.v_index + k, Vec3<S>::Unit(k));
          J.template block<3, 1>(3, b.v_index + 3 + k) = R.col(k);
        }
        break;
      case JointType::Spherical:
        for (int k = 0; k < 3; ++k) angular(b.v_index + k, Vec3<S>::Unit(k));
        break;
      case JointType::Revolute: angular(b.v_index, b.axis); break;
      case JointType::Fixed: break;
    }
  }
}

// 3 x nv Jacobian of the world velocity of a point fixed on body i (body coordinates).
template <class S, int MB, int MD, class Mat>
inline void point_jacobian(const Model<S, MB, MD>& m, const Data<S, MB, MD>& d, int i, const Vec3<S>& point_body,
                          Mat& J) {
  Eigen::Matrix<S, 6, Eigen::Dynamic, 0, 6, MD> Jb(6, J.cols());
  body_jacobian(m, d, i, point_body, Jb);
  J = Jb.template bottomRows<3>();
}

}  // namespace sparsebody::dynamics
