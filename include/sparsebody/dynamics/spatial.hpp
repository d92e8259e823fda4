// Spatial (6D) algebra in fixed-size Eigen, following Featherstone, "Rigid Body Dynamics Algorithms"
// (2008), ch. 2. Vectors are ordered (angular; linear): motion m = (w; v), force f = (n; f).
// Every type is fixed-size so nothing here allocates.
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace sparsebody::dynamics {

template <class S> using Vec3 = Eigen::Matrix<S, 3, 1>;
template <class S> using Vec6 = Eigen::Matrix<S, 6, 1>;
template <class S> using Mat3 = Eigen::Matrix<S, 3, 3>;
template <class S> using Mat6 = Eigen::Matrix<S, 6, 6>;
template <class S> using Mat63 = Eigen::Matrix<S, 6, 3>;
template <class S> using Quat = Eigen::Quaternion<S>;

// Skew-symmetric cross-product matrix: skew(a) b = a x b.
template <class S>
inline Mat3<S> skew(const Vec3<S>& a) {
  Mat3<S> m;
  m << S(0), -a.z(), a.y(), a.z(), S(0), -a.x(), -a.y(), a.x(), S(0);
  return m;
}

// Plucker transform B_X_A from frame A (parent) to frame B (child), stored as Featherstone's (E, r):
// E rotates A-coordinates into B-coordinates, r is B's origin expressed in A. As a 6x6 matrix
// X = [E 0; -E r^ E]. Storing (E, r) instead of 6x6 costs 24 multiplies per apply instead of 36.
template <class S>
struct Transform {
  Mat3<S> E = Mat3<S>::Identity();
  Vec3<S> r = Vec3<S>::Zero();

  // m_B = X m_A (motion vectors).
  Vec6<S> apply(const Vec6<S>& m) const {
    Vec6<S> out;
    out.template head<3>() = E * m.template head<3>();
    out.template tail<3>() = E * (m.template tail<3>() - r.cross(m.template head<3>()));
    return out;
  }
  // m_A = X^-1 m_B (motion vectors, child to parent).
  Vec6<S> applyInverse(const Vec6<S>& m) const {
    Vec6<S> out;
    out.template head<3>() = E.transpose() * m.template head<3>();
    out.template tail<3>() = E.transpose() * m.template tail<3>() + r.cross(Vec3<S>(out.template head<3>()));
    return out;
  }
  // f_A = X^T f_B: a force on the child expressed in the parent (X^* inverse = X^T).
  Vec6<S> applyTransposeForce(const Vec6<S>& f) const {
    Vec6<S> out;
    out.template tail<3>() = E.transpose() * f.template tail<3>();
    out.template head<3>() = E.transpose() * f.template head<3>() + r.cross(Vec3<S>(out.template tail<3>()));
    return out;
  }
  // Composition: (this * other) = C_X_A when this = C_X_B and other = B_X_A.
  Transform operator*(const Transform& o) const {
    Transform t;
    t.E = E * o.E;
    t.r = o.r + o.E.transpose() * r;
    return t;
  }
  Mat6<S> matrix() const {
    Mat6<S> X = Mat6<S>::Zero();
    X.template topLeftCorner<3, 3>() = E;
    X.template bottomRightCorner<3, 3>() = E;
    X.template bottomLeftCorner<3, 3>() = -E * skew(r);
    return X;
  }
};

// Articulated/rigid inertia expressed in the child, moved to the parent: I_A = X^T I_B X.
// With I = [A B; B^T C] the rotated blocks A' = E^T A E etc. are then shifted by r:
//   A_p = A' - B' r^ + r^ B'^T - r^ C' r^,  B_p = B' + r^ C',  C_p = C'.
// All 3x3 products; about 3x cheaper than two dense 6x6 products.
template <class S>
inline void addTransformedInertia(const Transform<S>& X, const Mat6<S>& I, Mat6<S>& out) {
  const Mat3<S> Et = X.E.transpose();
  const Mat3<S> A = Et * I.template topLeftCorner<3, 3>() * X.E;
  const Mat3<S> B = Et * I.template topRightCorner<3, 3>() * X.E;
  const Mat3<S> C = Et * I.template bottomRightCorner<3, 3>() * X.E;
  const Mat3<S> rx = skew(X.r);
  const Mat3<S> rxC = rx * C;
  const Mat3<S> Bp = B + rxC;
  const Mat3<S> Bprx = B * rx;
  const Mat3<S> Ap = A - Bprx - Bprx.transpose() - rxC * rx;  // r^ B^T = -(B r^)^T
  out.template topLeftCorner<3, 3>() += Ap;
  out.template topRightCorner<3, 3>() += Bp;
  out.template bottomLeftCorner<3, 3>() += Bp.transpose();
  out.template bottomRightCorner<3, 3>() += C;
}

// Spatial cross products: v x m (motion) and v x* f (force), Featherstone eq. 2.31-2.32.
template <class S>
inline Vec6<S> crossMotion(const Vec6<S>& v, const Vec6<S>& m) {
  const Vec3<S> w = v.template head<3>(), vo = v.template tail<3>();
  const Vec3<S> mw = m.template head<3>(), mv = m.template tail<3>();
  Vec6<S> out;
  out.template head<3>() = w.cross(mw);
  out.template tail<3>() = w.cross(mv) + vo.cross(mw);
  return out;
}
template <class S>
inline Vec6<S> crossForce(const Vec6<S>& v, const Vec6<S>& f) {
  const Vec3<S> w = v.template head<3>(), vo = v.template tail<3>();
  const Vec3<S> fn = f.template head<3>(), ff = f.template tail<3>();
  Vec6<S> out;
  out.template head<3>() = w.cross(fn) + vo.cross(ff);
  out.template tail<3>() = w.cross(ff);
  return out;
}

// Rigid-body spatial inertia about the body origin from mass m, centre of mass c and the
// rotational inertia Ic about c (all in body coordinates): I = [Ic - m c^c^, m c^; -m c^, m 1].
template <class S>
inline Mat6<S> rigidInertia(S m, const Vec3<S>& c, const Mat3<S>& Ic) {
  const Mat3<S> cx = skew(c);
  Mat6<S> I;
  I.template topLeftCorner<3, 3>() = Ic - m * cx * cx;
  I.template topRightCorner<3, 3>() = m * cx;
  I.template bottomLeftCorner<3, 3>() = -m * cx;
  I.template bottomRightCorner<3, 3>() = m * Mat3<S>::Identity();
  return I;
}

// Quaternion exponential map: rotation by the rotation vector w (angle |w|), exact for all |w|.
template <class S>
inline Quat<S> quatExp(const Vec3<S>& w) {
  const S th = w.norm();
  const S half = S(0.5) * th;
  // sin(half)/th with a Taylor series near 0 so tiny rotations stay exact.
  const S k = th < S(1e-6) ? S(0.5) - th * th / S(48) : std::sin(half) / th;
  return Quat<S>(std::cos(half), k * w.x(), k * w.y(), k * w.z());
}
// Logarithm: the rotation vector of q, taking the short way (|angle| <= pi).
template <class S>
inline Vec3<S> quatLog(Quat<S> q) {
  if (q.w() < S(0)) q.coeffs() = -q.coeffs();
  const Vec3<S> v = q.vec();
  const S s = v.norm();
  if (s < S(1e-8)) return S(2) * v / q.w();  // angle ~ 2 s / w
  const S angle = S(2) * std::atan2(s, q.w());
  return (angle / s) * v;
}

}  // namespace sparsebody::dynamics
