// Stance support of the Neural3Points model-based controller (model_based_controller.hpp): the
// floor carries the root wrench w_root = (N, F) that RNEA asks of the unactuated root. It is handed
// to the feet in contact, shared by the contact weights c_L, c_R (w_s = c_s / (c_L + c_R) w_root),
// and the stance legs carry it:
//   tau_leg(s) -= J_s^T w_s     (RNEA with external forces: tau = M qdd + C - J^T f_ext)
// on the DoFs of UpperLeg, LowerLeg, Foot, J_s the foot's Jacobian at the root origin, so the moment
// N is carried too (`moment`; without it the legs let the body tip).
// Per call: no allocation (the Jacobian has fixed storage), no exception.
#pragma once
#include <algorithm>

#include "sparsebody/dynamics/jacobian.hpp"

namespace sparsebody::control {

template <class S, int MB, int MD>
class StanceSupport {
 public:
  using ModelT = dynamics::Model<S, MB, MD>;
  using VecV = typename ModelT::VecV;
  using Vec3 = dynamics::Vec3<S>;

  StanceSupport() = default;
  // The legs of Foot_L / Foot_R up to (not including) the root body; a missing foot gets no support.
  StanceSupport(const ModelT& m, int root) : root_(root) {
    const char* feet[2] = {"Foot_L", "Foot_R"};
    for (int s = 0; s < 2; ++s) {
      foot_[s] = m.find(feet[s]);
      int n = 0;
      for (int b = foot_[s]; b >= 0 && b != root_ && n < 3; b = m.bodies[b].parent) leg_[s][n++] = b;
      leg_len_[s] = foot_[s] >= 0 ? n : 0;
    }
  }

  // tau_leg -= J^T w on the stance legs: F, N the root wrench (world, N about the root origin),
  // contact the weights c_L, c_R (no support below a total of 0.1: flight), J from the
  // kinematics in dd.
  void apply(const ModelT& m, const dynamics::Data<S, MB, MD>& dd, const Vec3& F, const Vec3& N, const double (&contact)[2],
             bool moment, VecV& tau) noexcept {
    const double cs = std::max(0.0, contact[0]) + std::max(0.0, contact[1]);
    if (!(cs > 0.1)) return;  // flight: no support
    for (int s = 0; s < 2; ++s) {
      if (leg_len_[s] == 0 || !(contact[s] > 0)) continue;
      const S share = S(contact[s] / cs);
      J_.resize(6, m.nv);
      // The root wrench (N about the root origin, F) received by the foot: its Jacobian at the root origin.
      const Vec3 at = moment ? Vec3(dd.R[foot_[s]].transpose() * (dd.p[root_] - dd.p[foot_[s]])) : Vec3::Zero();
      dynamics::body_jacobian(m, dd, foot_[s], at, J_);
      for (int c = 0; c < leg_len_[s]; ++c) {
        const dynamics::Body<S>& b = m.bodies[leg_[s][c]];
        for (int k = 0; k < m.nv_of(leg_[s][c]); ++k) {
          S t = Vec3(J_.template block<3, 1>(3, b.v_index + k)).dot(share * F);
          if (moment) t += Vec3(J_.template block<3, 1>(0, b.v_index + k)).dot(share * N);
          tau(b.v_index + k) -= t;
        }
      }
    }
  }

 private:
  int root_ = 0;
  int foot_[2] = {-1, -1}, leg_[2][3] = {}, leg_len_[2] = {};
  Eigen::Matrix<S, 6, Eigen::Dynamic, 0, 6, MD> J_;
};

}  // namespace sparsebody::control
