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

// Parent->child transform X = X_J(q) X_T as plain scalars: E column-major in e[9] (E(r, c) =
// e[r + 3 c]), r in r[3]. The child orientation in the parent is R_T R_J, so E = (R_T R_J)^T =
// R_J^T E_T; the product is skipped when X_T has no rotation (the usual case). The free root
// ignores X_T (its coordinates are the pose itself).
// Scalars, not an Eigen Transform: the first pass uses E right after computing it, and read back
// from memory by packed loads just after scalar stores it stalled on store forwarding (a third of
// forward_kinematics on Zen 4).
template <class S, int MB, int MD>
SPARSEBODY_INLINE void joint_transform(const Model<S, MB, MD>& m, int i, const typename Model<S, MB, MD>::VecQ& q, S* e, S* r) {
  const Body<S>& b = m.bodies[i];
  const int k = b.q_index;
  r[0] = b.XT.r.x();
  r[1] = b.XT.r.y();
  r[2] = b.XT.r.z();
  switch (b.joint) {
    case JointType::Free:
      quat_to_transposed_rotation(q(k + 3), q(k + 4), q(k + 5), q(k + 6), e);
      r[0] = q(k);
      r[1] = q(k + 1);
      r[2] = q(k + 2);
      return;
    case JointType::Spherical: quat_to_transposed_rotation(q(k), q(k + 1), q(k + 2), q(k + 3), e); break;
    case JointType::Revolute: {  // E = R^T = cos 1 - sin [a]x + (1 - cos) a a^T
      const S c = std::cos(q(k)), sn = std::sin(q(k)), t = S(1) - c;
      const S ax = b.axis.x(), ay = b.axis.y(), az = b.axis.z();
      e[0] = c + t * ax * ax;      e[3] = t * ax * ay + sn * az; e[6] = t * ax * az - sn * ay;
      e[1] = t * ax * ay - sn * az; e[4] = c + t * ay * ay;      e[7] = t * ay * az + sn * ax;
      e[2] = t * ax * az + sn * ay; e[5] = t * ay * az - sn * ax; e[8] = c + t * az * az;
      break;
    }
    case JointType::Fixed:
      for (int j = 0; j < 9; ++j) e[j] = b.XT.E.data()[j];
      return;
  }
  if (!b.XT_identity) {  // E <- E E_T
    S o[9];
    const Mat3<S>& T = b.XT.E;
    for (int c = 0; c < 3; ++c)
      for (int rr = 0; rr < 3; ++rr) o[rr + 3 * c] = e[rr] * T(0, c) + e[rr + 3] * T(1, c) + e[rr + 6] * T(2, c);
    for (int j = 0; j < 9; ++j) e[j] = o[j];
  }
}
template <class S, int MB, int MD>
SPARSEBODY_INLINE void joint_transform(const Model<S, MB, MD>& m, int i, const typename Model<S, MB, MD>::VecQ& q, Transform<S>& X) {
  S e[9], r[3];
  joint_transform(m, i, q, e, r);
  for (int j = 0; j < 9; ++j) X.E.data()[j] = e[j];
  X.r = Vec3<S>(r[0], r[1], r[2]);
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
// X_i, v_i and c_i are computed in scalars and stored once (see joint_transform).
template <class S, int MB, int MD>
inline void forward_kinematics(const Model<S, MB, MD>& m, Data<S, MB, MD>& d,
                              const typename Model<S, MB, MD>::VecQ& q,
                              const typename Model<S, MB, MD>::VecV* qd, bool with_world = true) {
  for (int i = 0; i < m.nb; ++i) {
    const Body<S>& b = m.bodies[i];
    const int pi = b.parent;
    S e[9], r[3];
    joint_transform(m, i, q, e, r);
    Transform<S>& X = d.X[i];
    for (int j = 0; j < 9; ++j) X.E.data()[j] = e[j];
    X.r = Vec3<S>(r[0], r[1], r[2]);
    if (with_world) {
      if (pi < 0) {
        d.R[i] = X.E.transpose();
        d.p[i] = X.r;
      } else {
        d.R[i].noalias() = d.R[pi] * X.E.transpose();
        d.p[i].noalias() = d.p[pi] + d.R[pi] * X.r;
      }
    }
    if (!qd) continue;
    Vec6<S>& v = d.v[i];
    Vec6<S>& c = d.c[i];
    const int k = b.v_index;
    if (pi < 0) {
      if (b.joint == JointType::Free) {
        for (int t = 0; t < 6; ++t) v(t) = (*qd)(k + t);
      } else {
        v = joint_velocity(m, i, *qd);
      }
      c.setZero();  // v x vJ = vJ x vJ = 0 at the root
      continue;
    }
    // v = X v_lambda + S qd. S is constant in body coordinates, so c = v x S qd; for spherical and
    // revolute joints vJ = (w_J, 0), hence c = (w x w_J, v_lin x w_J).
    S o[6];
    apply_motion(e, r, d.v[pi].data(), o);
    S j0 = S(0), j1 = S(0), j2 = S(0);  // w_J
    if (b.joint == JointType::Spherical) {
      j0 = (*qd)(k);
      j1 = (*qd)(k + 1);
      j2 = (*qd)(k + 2);
    } else if (b.joint == JointType::Revolute) {
      const S x = (*qd)(k);
      j0 = b.axis.x() * x;
      j1 = b.axis.y() * x;
      j2 = b.axis.z() * x;
    }
    o[0] += j0;
    o[1] += j1;
    o[2] += j2;
    for (int t = 0; t < 6; ++t) v(t) = o[t];
    c(0) = o[1] * j2 - o[2] * j1;
    c(1) = o[2] * j0 - o[0] * j2;
    c(2) = o[0] * j1 - o[1] * j0;
    c(3) = o[4] * j2 - o[5] * j1;
    c(4) = o[5] * j0 - o[3] * j2;
    c(5) = o[3] * j1 - o[4] * j0;
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
