// Spatial (6D) algebra in fixed-size Eigen, following Featherstone, "Rigid Body Dynamics Algorithms"
// (2008), ch. 2. Vectors are ordered (angular; linear): motion m = (w; v), force f = (n; f).
// Every type is fixed-size so nothing here allocates.
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <type_traits>

// Full unrolling of the small fixed-trip loops of the hot kernels (GCC leaves triangular nests rolled).
#if defined(__GNUC__) || defined(__clang__)
#define SPARSEBODY_UNROLL _Pragma("GCC unroll 8")
#else
#define SPARSEBODY_UNROLL
#endif
// Small hot kernels are always inlined: left to the inliner, whether they are would depend on how
// much other code the including translation unit has.
#if defined(__GNUC__) || defined(__clang__)
#define SPARSEBODY_INLINE inline __attribute__((always_inline))
#else
#define SPARSEBODY_INLINE inline
#endif

namespace sparsebody::dynamics {

// Two values that go through the same arithmetic, one per lane, in half the instructions: RNEA's
// I a and I v (one inertia times two vectors), a force's two halves under one rotation. GCC/Clang
// vector extensions for float and double (SSE2 / NEON registers); other scalar types and
// compilers get a plain pair. Lanes are read as p[0], p[1].
template <class S>
struct Lanes2Of {
  struct type {
    S v[2];
    S operator[](int k) const { return v[k]; }
    friend type operator+(type a, type b) { return {{a.v[0] + b.v[0], a.v[1] + b.v[1]}}; }
    friend type operator-(type a, type b) { return {{a.v[0] - b.v[0], a.v[1] - b.v[1]}}; }
    friend type operator*(S a, type b) { return {{a * b.v[0], a * b.v[1]}}; }
  };
  static type make(S a, S b) { return {{a, b}}; }
  static constexpr bool vector = false;  // a plain pair: code with a one-lane form uses that instead
};
#if defined(__GNUC__) || defined(__clang__)
template <>
struct Lanes2Of<double> {
  typedef double type __attribute__((vector_size(16)));
  static type make(double a, double b) { return type{a, b}; }
  static constexpr bool vector = true;
};
template <>
struct Lanes2Of<float> {
  typedef float type __attribute__((vector_size(8)));
  static type make(float a, float b) { return type{a, b}; }
  static constexpr bool vector = true;
};
#endif
template <class S>
using Lanes2 = typename Lanes2Of<S>::type;

// Code written once for one body (N = 1, values S) and for two at once (N = 2, values Lanes2<S>,
// lane k holding body k's value): ABA's paired steps (Model::backward_steps).
template <class S, int N>
using Lane = std::conditional_t<N == 1, S, Lanes2<S>>;
// The lane value whose lane k is f(k).
template <class S, int N, class F>
SPARSEBODY_INLINE Lane<S, N> gather(const F& f) {
  if constexpr (N == 1) {
    return f(0);
  } else {
    return Lanes2Of<S>::make(f(0), f(1));
  }
}
template <int N, class V>
SPARSEBODY_INLINE auto lane(const V& v, [[maybe_unused]] int k) {
  if constexpr (N == 1) {
    return v;
  } else {
    return v[k];
  }
}

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

// out = X m for a motion vector, X = (E, r) given as E column-major in e[9] (E(i, j) = e[i + 3 j])
// and r[3]: Transform::apply, and forward kinematics on an X still in registers. Written out by
// component: for 3-vectors Eigen's packet code (AVX-512 here) costs more than it saves, and this
// runs ~4 times per body per ABA call. m and out distinct.
template <class S>
SPARSEBODY_INLINE void apply_motion(const S* e, const S* r, const S* m, S* out) noexcept {
  const S wx = m[0], wy = m[1], wz = m[2];
  const S ux = m[3] - (r[1] * wz - r[2] * wy);  // v - r x w
  const S uy = m[4] - (r[2] * wx - r[0] * wz);
  const S uz = m[5] - (r[0] * wy - r[1] * wx);
  out[0] = e[0] * wx + e[3] * wy + e[6] * wz;
  out[1] = e[1] * wx + e[4] * wy + e[7] * wz;
  out[2] = e[2] * wx + e[5] * wy + e[8] * wz;
  out[3] = e[0] * ux + e[3] * uy + e[6] * uz;
  out[4] = e[1] * ux + e[4] * uy + e[7] * uz;
  out[5] = e[2] * ux + e[5] * uy + e[8] * uz;
}

// Plucker transform B_X_A from frame A (parent) to frame B (child), stored as Featherstone's (E, r):
// E rotates A-coordinates into B-coordinates, r is B's origin expressed in A. As a 6x6 matrix
// X = [E 0; -E r^ E]. Storing (E, r) instead of 6x6 costs 24 multiplies per apply instead of 36.
template <class S>
struct Transform {
  Mat3<S> E = Mat3<S>::Identity();
  Vec3<S> r = Vec3<S>::Zero();

  // m_B = X m_A (motion vectors), by component (apply_motion above).
  SPARSEBODY_INLINE Vec6<S> apply(const Vec6<S>& m) const {
    Vec6<S> out;
    apply_motion(E.data(), r.data(), m.data(), out.data());
    return out;
  }
  // The same on plain arrays (m and out distinct), for passes that keep vectors in scalars.
  SPARSEBODY_INLINE void apply(const S* m, S* out) const { apply_motion(E.data(), r.data(), m, out); }
  // m_A = X^-1 m_B (motion vectors, child to parent).
  SPARSEBODY_INLINE Vec6<S> apply_inverse(const Vec6<S>& m) const {
    Vec6<S> out;
    for (int k = 0; k < 3; ++k) {
      out(k) = E(0, k) * m(0) + E(1, k) * m(1) + E(2, k) * m(2);
      out(3 + k) = E(0, k) * m(3) + E(1, k) * m(4) + E(2, k) * m(5);
    }
    out(3) += r.y() * out(2) - r.z() * out(1);  // + r x w_A
    out(4) += r.z() * out(0) - r.x() * out(2);
    out(5) += r.x() * out(1) - r.y() * out(0);
    return out;
  }
  // f_A = X^T f_B: a force on the child expressed in the parent (X^* inverse = X^T).
  SPARSEBODY_INLINE Vec6<S> apply_transpose_force(const Vec6<S>& f) const {
    Vec6<S> out;
    apply_transpose_force(f.data(), out.data());
    return out;
  }
  // The same on plain arrays (f and out distinct).
  SPARSEBODY_INLINE void apply_transpose_force(const S* f, S* out) const {
    // E^T n and E^T f in the two lanes of one product
    const Lanes2<S> f0 = Lanes2Of<S>::make(f[0], f[3]), f1 = Lanes2Of<S>::make(f[1], f[4]), f2 = Lanes2Of<S>::make(f[2], f[5]);
    for (int k = 0; k < 3; ++k) {
      const Lanes2<S> o = E(0, k) * f0 + E(1, k) * f1 + E(2, k) * f2;
      out[k] = o[0];
      out[3 + k] = o[1];
    }
    out[0] += r.y() * out[5] - r.z() * out[4];
    out[1] += r.z() * out[3] - r.x() * out[5];
    out[2] += r.x() * out[4] - r.y() * out[3];
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
// Small dense products written as plain loops: for 3x3 blocks they compile to straight-line FMAs,
// which beats Eigen's packet path at this size.
template <class S>
SPARSEBODY_INLINE Mat3<S> mul33(const Mat3<S>& A, const Mat3<S>& B) {  // A B
  Mat3<S> C;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) C(i, j) = A(i, 0) * B(0, j) + A(i, 1) * B(1, j) + A(i, 2) * B(2, j);
  return C;
}
template <class S>
SPARSEBODY_INLINE Mat3<S> mul_t33(const Mat3<S>& A, const Mat3<S>& B) {  // A^T B
  Mat3<S> C;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) C(i, j) = A(0, i) * B(0, j) + A(1, i) * B(1, j) + A(2, i) * B(2, j);
  return C;
}
// Inverse of a symmetric 3x3 matrix by cofactors (D_i of a spherical joint is SPD), from its lower
// triangle (a, b, c, e, f, g) = (D00, D10, D20, D11, D21, D22) into R (both triangles). Returns
// 1 / det(D). Plain arrays so that ABA keeps D^-1 in registers. S may be Lanes2 (two matrices).
template <class S>
SPARSEBODY_INLINE S inverse_sym3(S a, S b, S c, S e, S f, S g, S (&R)[3][3]) noexcept {
  const S A = e * g - f * f, B = c * f - b * g, C = b * f - c * e;
  const S inv = 1 / (a * A + b * B + c * C);
  R[0][0] = A * inv;
  R[1][0] = R[0][1] = B * inv;
  R[2][0] = R[0][2] = C * inv;
  R[1][1] = (a * g - c * c) * inv;
  R[2][1] = R[1][2] = (b * c - a * f) * inv;
  R[2][2] = (a * e - b * b) * inv;
  return inv;
}

// Cholesky factor L (lower triangle written, L L^T = A) of a symmetric 6x6 matrix given by its
// lower triangle, unrolled, with the reciprocals of L's diagonal in inv_diag (the solve then
// multiplies instead of dividing). Returns false when a pivot is not positive (same criterion as
// Eigen::LLT's NumericalIssue).
template <class S>
inline bool cholesky_factor6(const Mat6<S>& A, Mat6<S>& L, Vec6<S>& inv_diag) noexcept {
  for (int j = 0; j < 6; ++j) {
    S djj = A(j, j);
    for (int k = 0; k < j; ++k) djj -= L(j, k) * L(j, k);
    if (!(djj > S(0))) return false;
    const S ljj = std::sqrt(djj);
    L(j, j) = ljj;
    const S inv = S(1) / ljj;
    inv_diag(j) = inv;
    for (int i = j + 1; i < 6; ++i) {
      S s = A(i, j);
      for (int k = 0; k < j; ++k) s -= L(i, k) * L(j, k);
      L(i, j) = s * inv;
    }
  }
  return true;
}
// Solves (L L^T) x = b in place.
template <class S>
SPARSEBODY_INLINE void cholesky_solve6(const Mat6<S>& L, const Vec6<S>& inv_diag, Vec6<S>& x) noexcept {
  S y[6];
  SPARSEBODY_UNROLL for (int i = 0; i < 6; ++i) {
    S s = x(i);
    SPARSEBODY_UNROLL for (int k = 0; k < 6; ++k)
      if (k < i) s -= L(i, k) * y[k];
    y[i] = s * inv_diag(i);
  }
  SPARSEBODY_UNROLL for (int i = 5; i >= 0; --i) {
    S s = y[i];
    SPARSEBODY_UNROLL for (int k = 0; k < 6; ++k)
      if (k > i) s -= L(k, i) * y[k];
    y[i] = s * inv_diag(i);
  }
  SPARSEBODY_UNROLL for (int i = 0; i < 6; ++i) x(i) = y[i];
}

// r^ M (cross product of r with each column of M).
template <class S>
SPARSEBODY_INLINE Mat3<S> cross_mat(const Vec3<S>& r, const Mat3<S>& M) {
  Mat3<S> C;
  for (int j = 0; j < 3; ++j) {
    C(0, j) = r.y() * M(2, j) - r.z() * M(1, j);
    C(1, j) = r.z() * M(0, j) - r.x() * M(2, j);
    C(2, j) = r.x() * M(1, j) - r.y() * M(0, j);
  }
  return C;
}

// Element (r, c) of a symmetric matrix kept in its lower triangle (row >= column). With constant
// indices (the unrolled loops below) the choice is made at compile time.
template <class S>
SPARSEBODY_INLINE S sym_lower(const Mat6<S>& M, int r, int c) noexcept {
  return r >= c ? M(r, c) : M(c, r);
}

// The same congruence out += X^T I X on lower triangles only: reads I's lower triangle and adds to
// out's lower triangle, never touching either upper triangle (ABA's pass 2 keeps I^A this way:
// 21 instead of 36 entries read and written per body). Every loop has a constant trip count and
// is unrolled, so the triangle tests fold away and the kernel is straight-line code.
// The arithmetic is written once on lane values V: S for one body, Lanes2<S> for two bodies at once
// (ABA's paired pass 2). E(r, c) gives E's entries, I(r, c) I's lower triangle (r >= c), and
// add(r, c, x) takes the increments of out's lower triangle.
template <class V, class EAt, class IAt, class AddAt>
SPARSEBODY_INLINE void congruence_lower(const EAt& E, V rx, V ry, V rz, const IAt& I, const AddAt& add) noexcept {
  const auto Is = [&](int r, int c) { return r >= c ? I(r, c) : I(c, r); };
  // I = [A B; B^T C]: A(i,k) = Is(i, k), B(i,k) = I(3+k, i), C(i,k) = Is(3+i, 3+k)
  V AE[3][3], BE[3][3], CE[3][3];  // A E, B E, C E
  SPARSEBODY_UNROLL for (int j = 0; j < 3; ++j) {
    const V e0 = E(0, j), e1 = E(1, j), e2 = E(2, j);
    SPARSEBODY_UNROLL for (int i = 0; i < 3; ++i) {
      AE[i][j] = Is(i, 0) * e0 + Is(i, 1) * e1 + Is(i, 2) * e2;
      BE[i][j] = I(3, i) * e0 + I(4, i) * e1 + I(5, i) * e2;
      CE[i][j] = Is(3 + i, 3) * e0 + Is(3 + i, 4) * e1 + Is(3 + i, 5) * e2;
    }
  }
  V a[3][3], b[3][3], c[3][3];  // A' = E^T A E (lower), B' = E^T B E, C' = E^T C E (both triangles)
  SPARSEBODY_UNROLL for (int j = 0; j < 3; ++j)
    SPARSEBODY_UNROLL for (int i = 0; i < 3; ++i) {
      b[i][j] = E(0, i) * BE[0][j] + E(1, i) * BE[1][j] + E(2, i) * BE[2][j];
      if (i >= j) {
        a[i][j] = E(0, i) * AE[0][j] + E(1, i) * AE[1][j] + E(2, i) * AE[2][j];
        c[i][j] = c[j][i] = E(0, i) * CE[0][j] + E(1, i) * CE[1][j] + E(2, i) * CE[2][j];
      }
    }
  V rc[3][3], rb[3][3];  // r^ C', r^ B'^T
  SPARSEBODY_UNROLL for (int j = 0; j < 3; ++j) {
    rc[0][j] = ry * c[2][j] - rz * c[1][j];
    rc[1][j] = rz * c[0][j] - rx * c[2][j];
    rc[2][j] = rx * c[1][j] - ry * c[0][j];
    rb[0][j] = ry * b[j][2] - rz * b[j][1];
    rb[1][j] = rz * b[j][0] - rx * b[j][2];
    rb[2][j] = rx * b[j][1] - ry * b[j][0];
  }
  SPARSEBODY_UNROLL for (int j = 0; j < 3; ++j) {
    // A_p = A' + r^ B'^T + (r^ B'^T)^T + r^ (r^ C')^T; column j of the last is r x (row j of r^ C')
    const V q0 = rc[j][0], q1 = rc[j][1], q2 = rc[j][2];
    const V rcr[3] = {ry * q2 - rz * q1, rz * q0 - rx * q2, rx * q1 - ry * q0};
    SPARSEBODY_UNROLL for (int i = 0; i < 3; ++i) {
      if (i >= j) {
        add(i, j, a[i][j] + rb[i][j] + rb[j][i] + rcr[i]);
        add(3 + i, 3 + j, c[i][j]);
      }
      add(3 + j, i, b[i][j] + rc[i][j]);  // B_p = B' + r^ C', stored as its transpose below the diagonal
    }
  }
}
template <class S>
SPARSEBODY_INLINE void add_transformed_inertia_lower(const Transform<S>& X, const Mat6<S>& I, Mat6<S>& out) noexcept {
  congruence_lower<S>([&](int r, int c) { return X.E(r, c); }, X.r.x(), X.r.y(), X.r.z(),
                      [&](int r, int c) { return I(r, c); }, [&](int r, int c, S x) { out(r, c) += x; });
}

// out += X^T I X for a symmetric I (articulated or rigid inertia) and a symmetric out, both
// triangles of out kept (CRBA's composite inertias): the lower-triangle kernel above, then its
// lower triangle mirrored.
template <class S>
inline void add_transformed_inertia(const Transform<S>& X, const Mat6<S>& I, Mat6<S>& out) noexcept {
  add_transformed_inertia_lower(X, I, out);
  for (int c = 0; c < 6; ++c)
    for (int r = c + 1; r < 6; ++r) out(c, r) = out(r, c);
}

// y = M x for a symmetric M kept in its lower triangle.
template <class S>
SPARSEBODY_INLINE Vec6<S> mul6v_lower(const Mat6<S>& M, const Vec6<S>& x) noexcept {
  Vec6<S> y;
  SPARSEBODY_UNROLL for (int i = 0; i < 6; ++i) {
    S s = S(0);
    SPARSEBODY_UNROLL for (int k = 0; k < 6; ++k) s += sym_lower(M, i, k) * x(k);
    y(i) = s;
  }
  return y;
}

// Spatial cross products: v x m (motion) and v x* f (force), Featherstone eq. 2.31-2.32.
template <class S>
SPARSEBODY_INLINE Vec6<S> cross_motion(const Vec6<S>& v, const Vec6<S>& m) {
  const Vec3<S> w = v.template head<3>(), vo = v.template tail<3>();
  const Vec3<S> mw = m.template head<3>(), mv = m.template tail<3>();
  Vec6<S> out;
  out.template head<3>() = w.cross(mw);
  out.template tail<3>() = w.cross(mv) + vo.cross(mw);
  return out;
}

// Rigid-body spatial inertia about the body origin from mass m, centre of mass c and the
// rotational inertia Ic about c (all in body coordinates): I = [Ic - m c^c^, m c^; -m c^, m 1].
template <class S>
inline Mat6<S> rigid_inertia(S m, const Vec3<S>& c, const Mat3<S>& Ic) {
  const Mat3<S> cx = skew(c);
  Mat6<S> I;
  I.template topLeftCorner<3, 3>() = Ic - m * cx * cx;
  I.template topRightCorner<3, 3>() = m * cx;
  I.template bottomLeftCorner<3, 3>() = -m * cx;
  I.template bottomRightCorner<3, 3>() = m * Mat3<S>::Identity();
  return I;
}

// y = I x for a rigid-body inertia I = rigid_inertia(m, c, Ic) (every Body::I: Model::finalize), from
// its structure: I x = [Ibar w + h x u; m u - h x w] for x = (w; u), with Ibar = I's top-left block
// and h = m c read from I's top-right block (m c^). 24 products instead of 36. V is S, or Lanes2<S>
// for two vectors at once.
template <class S, class V>
SPARSEBODY_INLINE void mul_rigid_inertia(const Mat6<S>& I, const V* x, V* y) noexcept {
  const S mass = I(3, 3), hx = -I(1, 5), hy = I(0, 5), hz = -I(0, 4);
  const V w0 = x[0], w1 = x[1], w2 = x[2], u0 = x[3], u1 = x[4], u2 = x[5];
  y[0] = I(0, 0) * w0 + I(0, 1) * w1 + I(0, 2) * w2 + (hy * u2 - hz * u1);
  y[1] = I(1, 0) * w0 + I(1, 1) * w1 + I(1, 2) * w2 + (hz * u0 - hx * u2);
  y[2] = I(2, 0) * w0 + I(2, 1) * w1 + I(2, 2) * w2 + (hx * u1 - hy * u0);
  y[3] = mass * u0 - (hy * w2 - hz * w1);
  y[4] = mass * u1 - (hz * w0 - hx * w2);
  y[5] = mass * u2 - (hx * w1 - hy * w0);
}
// f = v x* h (Featherstone eq. 2.32) on plain arrays.
template <class S>
SPARSEBODY_INLINE void cross_force(const S* v, const S* h, S* f) noexcept {
  f[0] = (v[1] * h[2] - v[2] * h[1]) + (v[4] * h[5] - v[5] * h[4]);
  f[1] = (v[2] * h[0] - v[0] * h[2]) + (v[5] * h[3] - v[3] * h[5]);
  f[2] = (v[0] * h[1] - v[1] * h[0]) + (v[3] * h[4] - v[4] * h[3]);
  f[3] = v[1] * h[5] - v[2] * h[4];
  f[4] = v[2] * h[3] - v[0] * h[5];
  f[5] = v[0] * h[4] - v[1] * h[3];
}
// The same on Vec6 (Featherstone eq. 2.32).
template <class S>
SPARSEBODY_INLINE Vec6<S> cross_force(const Vec6<S>& v, const Vec6<S>& f) {
  Vec6<S> out;
  cross_force(v.data(), f.data(), out.data());
  return out;
}

// E = R(q)^T for a quaternion (w, x, y, z) of any non-zero norm (scaled by 2 / |q|^2, so a slightly
// unnormalised state never shears the rotation and no sqrt is needed), column-major into e[9]
// (E(i, j) = e[i + 3 j]).
template <class S>
SPARSEBODY_INLINE void quat_to_transposed_rotation(S w, S x, S y, S z, S* e) noexcept {
  const S s = 2 / (w * w + x * x + y * y + z * z);  // (S may be Lanes2)
  const S xx = s * x * x, yy = s * y * y, zz = s * z * z;
  const S xy = s * x * y, xz = s * x * z, yz = s * y * z;
  const S wx = s * w * x, wy = s * w * y, wz = s * w * z;
  e[0] = 1 - yy - zz; e[3] = xy + wz;     e[6] = xz - wy;
  e[1] = xy - wz;     e[4] = 1 - xx - zz; e[7] = yz + wx;
  e[2] = xz + wy;     e[5] = yz - wx;     e[8] = 1 - xx - yy;
}

// Quaternion exponential map: rotation by the rotation vector w (angle |w|), exact for all |w|.
template <class S>
inline Quat<S> quat_exp(const Vec3<S>& w) {
  const S th = w.norm();
  const S half = S(0.5) * th;
  // sin(half)/th with a Taylor series near 0 so tiny rotations stay exact.
  const S k = th < S(1e-6) ? S(0.5) - th * th / S(48) : std::sin(half) / th;
  return Quat<S>(std::cos(half), k * w.x(), k * w.y(), k * w.z());
}
// Logarithm: the rotation vector of q, taking the short way (|angle| <= pi).
template <class S>
inline Vec3<S> quat_log(Quat<S> q) {
  if (q.w() < S(0)) q.coeffs() = -q.coeffs();
  const Vec3<S> v = q.vec();
  const S s = v.norm();
  if (s < S(1e-8)) return S(2) * v / q.w();  // angle ~ 2 s / w
  const S angle = S(2) * std::atan2(s, q.w());
  return (angle / s) * v;
}

}  // namespace sparsebody::dynamics
