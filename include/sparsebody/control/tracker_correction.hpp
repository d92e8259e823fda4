// Tracker position correction (Neural3Points §6.2, Eq. (19)): a virtual PD force on each hand,
//   F_virtual = kp (p_tracker - p_hand) - kd v_hand,      kp = 1000, kd = 10,
// realised as joint torques by Jacobian-transpose control on the arm chain (Shoulder, UpperArm,
// LowerArm, Hand): tau_arm += J_hand^T F. No external force is applied, so the total external
// force and torque on the character stay zero and the simulation remains physically correct.
// |F| is clamped to `max_force` (not in the paper) so a lost or jumping controller cannot yank the
// arm; a controller marked absent gets no force. Runs at the simulation rate.
// Per step: no allocation (the Jacobian has fixed storage), no exception.
#pragma once
#include <array>
#include <string>

#include "sparsebody/core/error.hpp"
#include "sparsebody/dynamics/jacobian.hpp"

namespace sparsebody::control {

struct TrackerCorrectionConfig {
  double kp = 1000;        // N/m
  double kd = 10;          // N s/m
  double max_force = 300;  // N, |F| bound
  bool enabled = true;
};

template <class S, int MB, int MD>
class TrackerCorrection {
 public:
  using ModelT = dynamics::Model<S, MB, MD>;
  using VecV = typename ModelT::VecV;
  using Vec3 = dynamics::Vec3<S>;
  static constexpr int kChain = 4;

  explicit TrackerCorrection(const ModelT& m, TrackerCorrectionConfig cfg = {}) : cfg_(cfg) {
    const char* hands[2] = {"Hand_L", "Hand_R"};
    const int chest = m.find("Chest");
    for (int s = 0; s < 2; ++s) {
      hand_[s] = m.find(hands[s]);
      if (hand_[s] < 0 || chest < 0) throw LoadError("tracker_correction", std::string("model lacks ") + hands[s] + " or Chest");
      int n = 0;
      for (int b = hand_[s]; b >= 0 && b != chest && n < kChain; b = m.bodies[b].parent) chain_[s][n++] = b;
      chain_len_[s] = n;
    }
  }

  const TrackerCorrectionConfig& config() const noexcept { return cfg_; }
  TrackerCorrectionConfig& config() noexcept { return cfg_; }
  int hand_body(int side) const noexcept { return hand_[side]; }

  // Adds the arm torques for both hands to tau (after forward kinematics with velocities in d).
  // target[s]: tracker position in simulation coordinates; present[s]: false = no force.
  void apply(const ModelT& m, const dynamics::Data<S, MB, MD>& d, const Vec3 (&target)[2], const bool (&present)[2],
             VecV& tau) noexcept {
    force_[0] = force_[1] = 0;
    if (!cfg_.enabled) return;
    for (int s = 0; s < 2; ++s) {
      if (!present[s] || !target[s].allFinite()) continue;
      const int h = hand_[s];
      J_.resize(6, m.nv);
      const Vec3 origin = Vec3::Zero();
      dynamics::body_jacobian(m, d, h, origin, J_);
      const Vec3 p = d.p[h];
      const Vec3 v = dynamics::point_velocity(d, h, origin);
      Vec3 F = S(cfg_.kp) * (target[s] - p) - S(cfg_.kd) * v;  // Eq. (19)
      const S n = F.norm();
      if (n > S(cfg_.max_force)) F *= S(cfg_.max_force) / n;
      if (!F.allFinite()) continue;
      for (int c = 0; c < chain_len_[s]; ++c) {  // tau = J^T F on the arm chain's DoFs only
        const dynamics::Body<S>& b = m.bodies[chain_[s][c]];
        for (int k = 0; k < m.nv_of(chain_[s][c]); ++k)
          tau(b.v_index + k) += Vec3(J_.template block<3, 1>(3, b.v_index + k)).dot(F);
      }
      force_[s] = double(F.norm());
    }
  }

  double force(int side) const noexcept { return force_[side]; }  // |F| of the last step (N)

 private:
  TrackerCorrectionConfig cfg_;
  int hand_[2] = {-1, -1};
  int chain_[2][kChain] = {};
  int chain_len_[2] = {};
  Eigen::Matrix<S, 6, Eigen::Dynamic, 0, 6, MD> J_;
  double force_[2] = {};
};

}  // namespace sparsebody::control
