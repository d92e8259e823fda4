// Per-model workspace: everything the algorithms write, sized by the compile-time bounds and
// allocated once with the object. All quantities are in body coordinates unless noted.
#pragma once
#include <array>

#include <Eigen/Cholesky>

#include "sparsebody/dynamics/model.hpp"

namespace sparsebody::dynamics {

template <class S, int MaxBodies, int MaxDofs>
struct Data {
  using M = Model<S, MaxBodies, MaxDofs>;
  std::array<Transform<S>, MaxBodies> X{};      // i_X_lambda(i): parent -> body (X_J X_T)
  std::array<Mat3<S>, MaxBodies> R{};           // world orientation of body i (columns = body axes)
  std::array<Vec3<S>, MaxBodies> p{};           // world position of body i's origin
  std::array<Vec6<S>, MaxBodies> v{};           // spatial velocity
  std::array<Vec6<S>, MaxBodies> c{};           // velocity-product acceleration c_i = v_i x S_i qd_i
  std::array<Vec6<S>, MaxBodies> a{};           // spatial acceleration (gravity included, a_0 = -g)
  std::array<Vec6<S>, MaxBodies> f{};           // RNEA body force
  std::array<Vec6<S>, MaxBodies> bias{};        // v x* I v
  std::array<Mat6<S>, MaxBodies> IA{};          // articulated inertia I^A (ABA keeps its lower triangle only)
  std::array<Vec6<S>, MaxBodies> pA{};          // articulated bias force p^A
  std::array<Mat63<S>, MaxBodies> U{};          // U_i = I^A_i S_i (revolute: column 0; spherical: read from IA)
  std::array<Mat3<S>, MaxBodies> Dinv{};        // D_i^-1, D_i = S_i^T I^A_i S_i + diag(implicit_diagonal_i)
  std::array<Vec3<S>, MaxBodies> u{};           // u_i = tau_i - S_i^T p^A_i
  Mat6<S> root_L{};                             // Cholesky factor (lower) of the free root's I^A
  Vec6<S> root_L_inv_diag{};                    // 1 / diag(root_L)
  // External loads per body (body coordinates), filled by contact: a force f_ext and an
  // acceleration-dependent part -K_ext a (linearly implicit contact), i.e. an added inertia K_ext.
  std::array<Vec6<S>, MaxBodies> fext{};
  std::array<Mat6<S>, MaxBodies> Kext{};
  bool has_ext = false;
  // Per-DoF term ABA adds to D_i (the free root: to its 6x6 I^A), like Pinocchio's armature: the
  // simulator writes h (kd + damping) per joint DoF and h K_r on the free root (implicit damping:
  // implicit_damping_diagonal in pd_servo.hpp, and the root servo). Zero: plain forward dynamics.
  typename M::VecV implicit_diagonal;
  typename M::VecV qdd, tau;

  Data() = default;
  explicit Data(const M& m) { resize(m); }
  void resize(const M& m) {
    qdd.setZero(m.nv);
    tau.setZero(m.nv);
    implicit_diagonal.setZero(m.nv);
    clear_external();
  }
  void clear_external() {
    for (auto& x : fext) x.setZero();
    for (auto& x : Kext) x.setZero();
    has_ext = false;
  }
};

}  // namespace sparsebody::dynamics
