// Where the QuestSim character starts and restarts: its model's reference (neutral) pose, at rest,
// standing under the headset of a sensor frame and facing the headset's heading (OpenXR: the device
// looks along its -Z). The run-time pipeline (avatar/questsim.hpp) puts the character there at
// start and after every fall, failure or tracker reset; the training environment starts a share of
// its episodes there (training/questsim_env.hpp), so the policy learns to leave the pose it is
// reset to at run time, not only the mocap states of reference-state initialisation.
#pragma once
#include <cmath>

#include "sparsebody/control/questsim_observation.hpp"
#include "sparsebody/features/heading_frame.hpp"

namespace sparsebody::control {

// q: the model's neutral configuration on entry (root height as the model stands), on return with
// the root moved under the headset and turned to its heading.
template <class S, class VecQ>
inline void questsim_stand_under_headset(const QuestSimSensorFrame<S>& frame, VecQ& q) noexcept {
  const dynamics::Vec3<S> fwd = -frame[0].rotation.col(2);
  const S theta = features::heading_angle(fwd, S(1e-6));
  q(0) = frame[0].position.x();
  q(2) = frame[0].position.z();
  q(3) = std::cos(theta / 2); q(4) = S(0); q(5) = std::sin(theta / 2); q(6) = S(0);  // R_y(theta)
}

}  // namespace sparsebody::control
