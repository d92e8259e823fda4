// Settings of the Neural3Points model-based controller (control/model_based_controller.hpp) and
// of how the physics pipeline drives it (avatar/n3p_physics.hpp, ControllerKind::ModelBased).
// The defaults were chosen on the validation clips with examples/n3p_physics_eval.cpp (its flags
// set each field; README, Neural3Points physics mode: the figures).
#pragma once

namespace sparsebody::control {

struct ModelBasedControllerConfig {
  // Residual gains: the simulator's root servo gains (dynamics::RootServo, same names).
  double kp_linear = 5000;   // N/m       residual force, position gain (p_ref - p)
  double kd_linear = 1000;   // N s/m     residual force, velocity gain
  double kp_angular = 1000;  // N m/rad   residual torque, orientation gain
  double kd_angular = 100;   // N m s/rad residual torque, angular velocity gain
  bool ground_reference = true;    // root target lifted out of the floor (ground_lift())
  double max_ground_lift = 0.1;    // m
  // Bounds. The default force bound is the avatar's weight (63 kg x 9.81 = 618 N): the help can at
  // most hold the body up, never throw it (README: falls and MPJPE against the bound).
  double max_force = 620;    // N   |F| bound
  double max_torque = 250;   // N m |N| bound
  double feedforward_scale = 1.0;  // 0 disables the inverse-dynamics feed-forward
  bool stance_support = true;      // the stance legs carry the root wrench RNEA asks for (J^T w)
  bool support_moment = true;      // ... its moment too, not only its force
  double acceleration_scale = 0.5; // weight of the finite-differenced qdd_ref in RNEA (30 Hz second
                                   // differences are noisy: the full weight tracks worse)
  // How the pipeline (avatar/n3p_physics.hpp) drives this controller:
  // - per_frame_targets: PD targets refreshed every frame to the reference `target_lead` frames
  //   ahead of the frame being tracked, instead of held for 3 frames (the policy's 10 Hz, §7);
  //   a lead makes up for the servos' lag. `--hold-targets 1` / `--target-lead` in the evaluation.
  // - velocity_targets: the servos' velocity targets qd* = the reference velocity (every frame),
  //   so kd damps the lag behind the motion instead of the motion itself.
  // - ground_resets: a (re)start or fall reset puts the character on the reference lifted out of
  //   the floor (ground_lift()), not into it.
  // - support_on_contact: the stance support's share of a foot is its predicted contact c only
  //   while the simulated foot touches the ground, 0 in the air (a foot in the air cannot carry
  //   the body).
  bool per_frame_targets = true;
  int target_lead = 2;
  bool velocity_targets = true;
  bool support_on_contact = true;
  bool ground_resets = true;
};

}  // namespace sparsebody::control
