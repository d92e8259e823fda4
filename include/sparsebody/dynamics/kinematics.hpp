// Forward kinematics: joint transforms, world poses, spatial velocities and the velocity-product
// terms c_i used by RNEA and ABA (Featherstone Table 5.1 / 7.1, first pass).
#pragma once
#include "sparsebody/dynamics/data.hpp"

namespace sparsebody::dynamics {

// Quaternion stored as (w, x, y, z) at q[k]; normalised on read so small drift never shears.
template <class S, class VecQ>
SPARSEBODY_INLINE Quat<S> read_quat(const VecQ& q, int k) {
  Quat<S> r(q(k), q(k + 1), q(k + 2), q(k + 3));
  const S n2 = r.squaredNorm();
  if (n2 > S(0)) r.coeffs() /= std::sqrt(n2);
  return r;
}

// Parent->child transform X = X_J(q) X_T, written into X. The child orientation in the parent is
// R_T R_J, so E = (R_T R_J)^T = R_J^T E_T; the product is skipped when X_T has no rotation (the
// usual case). The free root ignores X_T (its coordinates are the pose itself).
template <class S, int MB, int MD>
SPARSEBODY_INLINE void joint_transform(const Model<S, MB, MD>& m, int i, const typename Model<S, MB, MD>::VecQ& q, Transform<S>& X) {
  const Body<S>& b = m.bodies[i];
  const int k = b.q_index;
  X.r = b.XT.r;
  switch (b.joint) {
    case JointType::Free:
      quat_to_transposed_rotation(q(k + 3), q(k + 4), q(k + 5), q(k + 6), X.E);
      X.r = q.template segment<3>(k);
      return;
    case JointType::Spherical: quat_to_transposed_rotation(q(k), q(k + 1), q(k + 2), q(k + 3), X.E); break;
    case JointType::Revolute: X.E = Eigen::AngleAxis<S>(q(k), b.axis).toRotationMatrix().transpose(); break;
    case JointType::Fixed: X.E = b.XT.E; return;
  }
  if (!b.XT_identity) X.E = (X.E * b.XT.E).eval();
}
template <class S, int MB, int MD>
inline Transform<S> joint_transform(const Model<S, MB, MD>& m, int i, const typename Model<S, MB, MD>::VecQ& q) {
  Transform<S> X;
  joint_transform(m, i, q, X);
  return X;
}

// Motion subspace times joint velocity: v_J = S_i qd_i.
template <class S, int MB, int MD>
SPARSEBODY_INLINE Vec6<S> joint_velocity(const Model<S, MB, MD>& m, int i, const typename Model<S, MB, MD>::VecV& qd) {
  const Body<S>& b = m.bodies[i];
  Vec6<S> vJ = Vec6<S>::Zero();
  switch (b.joint) {
    case JointType::Free: vJ = qd.template segment<6>(b.v_index); break;
    case JointType::Spherical: vJ.template head<3>() = qd.template segment<3>(b.v_index); break;
    case JointType::Revolute: vJ.template head<3>() = b.axis * qd(b.v_index); break;
    case JointType::Fixed: break;
  }
  return vJ;
}

// Pass 1: X_i, world pose (R_i, p_i), v_i and c_i. Only positions when qd is null. ABA and RNEA
// alone do not need world poses and skip them (with_world = false) to save ~10 % of their time.
template <class S, int MB, int MD>
inline void forward_kinematics(const Model<S, MB, MD>& m, Data<S, MB, MD>& d,
                              const typename Model<S, MB, MD>::VecQ& q,
                              const typename Model<S, MB, MD>::VecV* qd, bool with_world = true) {
  for (int i = 0; i < m.nb; ++i) {
    const int pi = m.bodies[i].parent;
    joint_transform(m, i, q, d.X[i]);
    if (with_world) {
      if (pi < 0) {
        d.R[i] = d.X[i].E.transpose();
        d.p[i] = d.X[i].r;
      } else {
        d.R[i].noalias() = d.R[pi] * d.X[i].E.transpose();
        d.p[i].noalias() = d.p[pi] + d.R[pi] * d.X[i].r;
      }
    }
    if (qd) {
      const Body<S>& b = m.bodies[i];
      if (pi < 0) {
        d.v[i] = joint_velocity(m, i, *qd);
        d.c[i].setZero();  // v x vJ = vJ x vJ = 0 at the root
      } else {
        // S is constant in body coordinates, so c = v x S qd. For spherical/revolute joints
        // vJ = (w_J, 0), hence c = (w x w_J, v_lin x w_J).
        d.v[i] = d.X[i].apply(d.v[pi]);
        Vec3<S> wJ;
        if (b.joint == JointType::Spherical) wJ = qd->template segment<3>(b.v_index);
        else if (b.joint == JointType::Revolute) wJ = b.axis * (*qd)(b.v_index);
        else { d.c[i].setZero(); continue; }
        d.v[i].template head<3>() += wJ;
        const Vec3<S> w = d.v[i].template head<3>(), vl = d.v[i].template tail<3>();
        d.c[i].template head<3>() = w.cross(wJ);
        d.c[i].template tail<3>() = vl.cross(wJ);
      }
    }
  }
}

// World position and velocity of a point fixed on body i (point given in body coordinates);
// requires forward_kinematics with velocities.
template <class S, int MB, int MD>
inline Vec3<S> point_position(const Data<S, MB, MD>& d, int i, const Vec3<S>& p) {
  return d.p[i] + d.R[i] * p;
}
template <class S, int MB, int MD>
inline Vec3<S> point_velocity(const Data<S, MB, MD>& d, int i, const Vec3<S>& p) {
  const Vec6<S>& v = d.v[i];
  return d.R[i] * (Vec3<S>(v.template tail<3>()) + Vec3<S>(v.template head<3>()).cross(p));
}

// Centre of mass of the whole model (world), after forward_kinematics.
template <class S, int MB, int MD>
inline Vec3<S> center_of_mass(const Model<S, MB, MD>& m, const Data<S, MB, MD>& d) {
  Vec3<S> c = Vec3<S>::Zero();
  S mt = 0;
  for (int i = 0; i < m.nb; ++i) {
    c += m.bodies[i].mass * point_position(d, i, m.bodies[i].com);
    mt += m.bodies[i].mass;
  }
  return mt > S(0) ? Vec3<S>(c / mt) : c;
}

// Kinetic energy 1/2 sum v^T I v and gravitational potential -sum m g.c (world).
template <class S, int MB, int MD>
inline S kinetic_energy(const Model<S, MB, MD>& m, const Data<S, MB, MD>& d) {
  S T = 0;
  for (int i = 0; i < m.nb; ++i) T += S(0.5) * d.v[i].dot(m.bodies[i].I * d.v[i]);
  return T;
}
template <class S, int MB, int MD>
inline S potential_energy(const Model<S, MB, MD>& m, const Data<S, MB, MD>& d) {
  S U = 0;
  for (int i = 0; i < m.nb; ++i) U -= m.bodies[i].mass * m.gravity.dot(point_position(d, i, m.bodies[i].com));
  return U;
}
// Total spatial momentum (angular about the world origin; linear), world coordinates.
template <class S, int MB, int MD>
inline Vec6<S> spatial_momentum(const Model<S, MB, MD>& m, const Data<S, MB, MD>& d) {
  Vec6<S> h = Vec6<S>::Zero();
  for (int i = 0; i < m.nb; ++i) {
    const Vec6<S> hb = m.bodies[i].I * d.v[i];  // body-coordinates momentum about the body origin
    const Vec3<S> L = d.R[i] * hb.template tail<3>();
    h.template tail<3>() += L;
    h.template head<3>() += d.R[i] * hb.template head<3>() + d.p[i].cross(L);
  }
  return h;
}

}  // namespace sparsebody::dynamics
