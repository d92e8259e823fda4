// Semi-implicit (symplectic) Euler on the configuration manifold: the velocity is advanced first,
// qd+ = qd + h qdd, and the configuration moves with the new velocity:
//   revolute  theta+ = theta + h qd+
//   spherical Q+ = Q exp(h w+) (body-frame w: right multiplication), renormalised
//   free      Q+ = Q exp(h w+),  p+ = p + h vw+
// The free joint's linear velocity is advanced in the world frame and re-expressed in the new body
// frame, vw+ = R (v + h (dv + w x v)), v+ = R+^T vw+. Advancing the body-frame v directly would
// integrate its rotation term -w x v explicitly, which inflates |v| by sqrt(1 + (h|w|)^2) per step
// (a tumbling box at 60 rad/s gains 10 % speed per step at 120 Hz).
#pragma once
#include "sparsebody/dynamics/kinematics.hpp"

namespace sparsebody::dynamics {

template <class S, int MB, int MD>
inline void integrate(const Model<S, MB, MD>& m, typename Model<S, MB, MD>::VecQ& q, typename Model<S, MB, MD>::VecV& qd,
                      const typename Model<S, MB, MD>::VecV& qdd, S h) {
  auto rotate = [&](int k, const Vec3<S>& w) {
    Quat<S> Q = read_quat<S>(q, k) * quat_exp(Vec3<S>(h * w));
    Q.normalize();
    q(k) = Q.w(); q(k + 1) = Q.x(); q(k + 2) = Q.y(); q(k + 3) = Q.z();
  };
  for (int i = 0; i < m.nb; ++i) {
    const Body<S>& b = m.bodies[i];
    const int k = b.v_index;
    switch (b.joint) {
      case JointType::Free: {
        const Mat3<S> R = read_quat<S>(q, b.q_index + 3).toRotationMatrix();
        const Vec3<S> w = qd.template segment<3>(k), v = qd.template segment<3>(k + 3);
        const Vec3<S> vw = R * (v + h * (Vec3<S>(qdd.template segment<3>(k + 3)) + w.cross(v)));
        qd.template segment<3>(k) += h * qdd.template segment<3>(k);
        q.template segment<3>(b.q_index) += h * vw;
        rotate(b.q_index + 3, qd.template segment<3>(k));
        qd.template segment<3>(k + 3) = read_quat<S>(q, b.q_index + 3).toRotationMatrix().transpose() * vw;
        break;
      }
      case JointType::Spherical:
        qd.template segment<3>(k) += h * qdd.template segment<3>(k);
        rotate(b.q_index, qd.template segment<3>(k));
        break;
      case JointType::Revolute:
        qd(k) += h * qdd(k);
        q(b.q_index) += h * qd(k);
        break;
      case JointType::Fixed: break;
    }
  }
}

}  // namespace sparsebody::dynamics
