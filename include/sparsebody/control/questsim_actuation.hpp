// QuestSim action -> joint torques: tau_j = tau_max,j * clamp(a_j, -1, 1) on every non-root DoF.
// The paper (Winkler et al. 2022, Appendix A) maps [-1, 1] to [-200, 200] N m on every DoF of its
// IsaacGym character. On our avatar (de Leva masses: a hand 0.4 kg, toes 0.2 kg) 200 N m turns a
// light segment past the simulator's velocity limit within one 1/72 s substep, so exploration noise
// of a few per cent already ends many training episodes in a failed step (measured in the training
// environment: Gaussian noise of std 0.03 / 0.05 on a zero action -> 10 % / 25 % of control steps
// end in a failed substep). Per-joint limits in the proportions of DeepMimic's humanoid
// (Peng et al. 2018: hip 200, knee 150, ankle 90, chest 200, neck 50, shoulder 100, elbow 60 N m),
// with small ones for the wrists and toes, keep the same action range meaningful on every joint.
// Limits are for the default 1.75 m, 63 kg avatar and scale with mass x height (gravity torques
// scale so). `uniform` > 0 restores the paper's mapping (the same limit on every DoF).
#pragma once
#include <cmath>
#include <stdexcept>
#include <string_view>

#include "sparsebody/dynamics/model.hpp"

namespace sparsebody::control {

// Torque limit (N m) of the joint of the default avatar's body `name` (Hips: the free root, 0).
inline double questsim_default_torque_limit(std::string_view name) noexcept {
  struct Row { std::string_view prefix; double limit; };
  static constexpr Row rows[] = {
      {"Hips", 0},       {"Spine", 200},   {"Chest", 200},    {"Neck", 50},     {"Head", 30},
      {"Shoulder", 60},  {"UpperArm", 100}, {"LowerArm", 60}, {"Hand", 10},
      {"UpperLeg", 200}, {"LowerLeg", 150}, {"Foot", 90},     {"Toes", 10},
  };
  for (const Row& r : rows)
    if (name.substr(0, r.prefix.size()) == r.prefix) return r.limit;
  return 100;  // a body the table does not know (custom avatar): a middle value
}

// tau_max per velocity DoF of `m` (root entries 0). `height_ratio` = avatar height / 1.75 m;
// the limits scale by (total mass / 63 kg) x height_ratio. `uniform` > 0: that limit everywhere.
template <class S, int MB, int MD>
inline typename dynamics::Model<S, MB, MD>::VecV questsim_torque_limits(const dynamics::Model<S, MB, MD>& m,
                                                                       double height_ratio, double uniform = 0) {
  typename dynamics::Model<S, MB, MD>::VecV lim = dynamics::Model<S, MB, MD>::VecV::Zero(m.nv);
  double mass = 0;
  for (int i = 0; i < m.nb; ++i) mass += double(m.bodies[i].mass);
  const double k = (mass / 63.0) * height_ratio;
  for (int i = 0; i < m.nb; ++i) {
    const auto& b = m.bodies[i];
    if (b.joint == dynamics::JointType::Free) continue;
    const double l = uniform > 0 ? uniform : k * questsim_default_torque_limit(m.names[i]);
    for (int d = 0; d < m.nv_of(i); ++d) lim(b.v_index + d) = S(l);
  }
  return lim;
}

// The QuestSim joints' passive properties on every non-root body of `m` (the pipeline's avatar and
// the training environment's: one place, so a trained policy meets the same body at run time).
// Throws std::invalid_argument for a negative or non-finite damping or armature.
template <class S, int MB, int MD>
inline void set_questsim_joints(dynamics::Model<S, MB, MD>& m, double damping, double armature) {
  if (!(std::isfinite(damping) && damping >= 0) || !(std::isfinite(armature) && armature >= 0))
    throw std::invalid_argument("QuestSim joints: damping and armature must be finite and >= 0");
  for (int i = 1; i < m.nb; ++i) {
    m.bodies[i].damping = S(damping);
    m.bodies[i].armature = S(armature);
  }
  m.finalize();
}

}  // namespace sparsebody::control
