// Shared helpers for the dynamics tests: random states, relative errors, damped ABA.
#pragma once
#include <random>

#include "sparsebody/dynamics/aba.hpp"
#include "sparsebody/dynamics/kinematics.hpp"
#include "sparsebody/dynamics/pd_servo.hpp"

namespace dyn_test {
using namespace sparsebody::dynamics;

template <class Model>
void random_state(const Model& m, std::mt19937& rng, typename Model::VecQ& q, typename Model::VecV& qd,
                 double vel_scale = 2.0) {
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  q.resize(m.nq);
  qd.resize(m.nv);
  for (int i = 0; i < m.nb; ++i) {
    const auto& b = m.bodies[i];
    auto rand_quat = [&](int k) {
      Eigen::Vector4d v(n(rng), n(rng), n(rng), n(rng));
      v.normalize();
      for (int j = 0; j < 4; ++j) q(k + j) = v(j);
    };
    switch (b.joint) {
      case JointType::Free:
        for (int j = 0; j < 3; ++j) q(b.q_index + j) = u(rng);
        rand_quat(b.q_index + 3);
        break;
      case JointType::Spherical: rand_quat(b.q_index); break;
      case JointType::Revolute: q(b.q_index) = u(rng) * 2; break;
      default: break;
    }
  }
  for (int k = 0; k < m.nv; ++k) qd(k) = vel_scale * n(rng);
}

template <class A, class B>
double rel_err(const A& a, const B& b) {
  return (a - b).norm() / std::max(1.0, double(b.norm()));
}
// ABA with the simulator's implicit damping: h (kd + damping) per joint DoF (h damping alone
// without include_kd) and h K_r on the free root's DoFs when root_damping (K_r's diagonal) is given.
template <class S, int MB, int MD>
bool aba_damped(const Model<S, MB, MD>& m, Data<S, MB, MD>& d, const typename Model<S, MB, MD>::VecQ& q,
                const typename Model<S, MB, MD>::VecV& qd, const typename Model<S, MB, MD>::VecV& tau,
                typename Model<S, MB, MD>::VecV& qdd, S h, const Vec6<S>* root_damping = nullptr, bool include_kd = true) {
  implicit_damping_diagonal(m, h, include_kd, d.implicit_diagonal);
  if (m.root_body() >= 0 && root_damping)
    for (int r = 0; r < 6; ++r) d.implicit_diagonal(m.bodies[m.root_body()].v_index + r) = h * (*root_damping)(r);
  return aba(m, d, q, qd, tau, qdd);
}
}  // namespace dyn_test
