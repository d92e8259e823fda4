// Settings of the Neural3Points physics-mode pipeline (avatar/n3p_physics.hpp) and which controller
// sets its PD targets.
#pragma once
#include "sparsebody/avatar/n3p_direct.hpp"
#include "sparsebody/character/avatar.hpp"
#include "sparsebody/control/fall_detector.hpp"
#include "sparsebody/control/model_based_controller_config.hpp"
#include "sparsebody/control/tracker_correction.hpp"

namespace sparsebody::avatar {

// ModelBased: control/model_based_controller.hpp (default, no RL); Policy: the combined control
// predictor and a learned policy pi (control/n3p_control_predictor.hpp), when policy weights are given.
enum class ControllerKind : unsigned char { ModelBased, Policy };

// The reference's direct-mode settings: N3PConfig's, without head_height (a reference lifted off
// its feet by a headset higher than the body reaches would ask the simulated avatar to float; the
// physics figures were measured without it), and with the paper's ankle pin: a reference whose
// ankle turns about a pinned toe was tracked worse (n3p_physics_eval, every 3rd validation clip:
// MPJPE 8.49 -> 9.42 cm, residual force 243 -> 261 N, foot skating 23.9 -> 27.3 cm/s).
inline N3PConfig physics_reference_config() noexcept {
  N3PConfig c;
  c.head_height = false;
  c.pin = N3PConfig::Pin::Ankle;
  c.arm_reach.enabled = false;  // the simulated character's arms are the avatar's own
  return c;
}

struct N3PPhysicsConfig {
  N3PConfig direct = physics_reference_config();  // the reference: direct mode (foot pinning + arm IK)
  character::AvatarOptions avatar{};            // 1.75 m, 63 kg, kp 200, kd 20 (paper §7)
  control::ModelBasedControllerConfig controller{};  // ControllerKind::ModelBased only
  control::TrackerCorrectionConfig correction{};  // kp 1000, kd 10 (§6.2)
  control::FallDetectorConfig fall{};
  int substeps = 4;                  // simulation steps per 30 Hz frame (120 Hz)
  // Contact solves per simulation step (Simulator::contact.max_passes; the engine's default is 6).
  // On walking input the light-contact iterations of the feet do not settle (the sliding damper
  // and Fn feed each other back), so a step runs to the cap and its result depends on where it
  // stops; 3 fell least on the validation clips and is the fastest (README: the figures per cap).
  // `--contact-passes` in the evaluation.
  int contact_passes = 3;
  double max_reference_jump = 0.5;   // m per frame of the reference root; more restarts the physics
};

}  // namespace sparsebody::avatar
