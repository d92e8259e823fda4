// Settings of the QuestSim pipeline (avatar/questsim.hpp; Winkler et al. 2022, Appendix A) and the
// user height it scales the avatar to, estimated from a frame where the user stands upright (§3.6):
// h = headset height / eye_height_ratio (0.936: eye height over stature, Drillis & Contini 1966).
#pragma once
#include <cmath>

#include "sparsebody/trackers/sanitizer.hpp"
#include "sparsebody/trackers/types.hpp"

namespace sparsebody::avatar {

struct QuestSimConfig {
  double control_rate = 36.0;      // Hz: policy rate (Appendix A: 1/36 s)
  int substeps = 2;                // simulation substeps per control step (Appendix A)
  // Action -> torque (control/questsim_actuation.hpp): per-joint limits (DeepMimic's proportions,
  // scaled with the avatar), or with per_joint_torque_limits = false the paper's torque_scale on
  // every DoF (Appendix A: [-1, 1] -> [-200, 200] N m).
  bool per_joint_torque_limits = true;
  double torque_scale = 200.0;     // N m per unit of policy output when !per_joint_torque_limits
  double joint_damping = 0.1;      // passive joint damping, N m s/rad (Appendix A: "friction of 0.1")
  // Rotor inertia on every joint DoF, kg m^2 (dynamics::Body::armature): without it a torque held
  // for a whole control step spins the light twist axes and toes past the velocity limit whenever
  // the policy feeds back their motion (dynamics/README.md, "Armature"). The training environment
  // uses the same value, so a policy trained there meets the same body here.
  double joint_armature = 0.05;
  double eye_height_ratio = 0.936; // standing headset height / stature
  double min_height = 1.0, max_height = 2.4;  // heights accepted by user_height_from_headset (m)
  double fall_height_ratio = 0.5;  // root below this fraction of its standing height: fallen
  double fall_tilt = 1.2;          // rad (~69 deg): root up-axis tilt beyond this: fallen
  // (both checked by control::FallDetector without a reference: QuestSimPipeline::fall_detector_config())
  double max_gap = 0.25;           // s: resampler time gap that restarts
  trackers::SanitizerConfig sanitizer{};
};

// User height (m) from a frame where the user stands upright: headset height / eye_height_ratio.
// NaN when the headset is invalid or non-finite, or the height is outside [min_height, max_height].
inline double user_height_from_headset(const trackers::TrackerFrame& standing, const QuestSimConfig& cfg = {}) noexcept {
  const int H = static_cast<int>(trackers::Tracker::Head);
  const double y = standing.pose[H].position.y;
  if (!standing.valid[H] || !std::isfinite(y)) return std::nan("");
  const double h = y / cfg.eye_height_ratio;
  return (h >= cfg.min_height && h <= cfg.max_height) ? h : std::nan("");
}

}  // namespace sparsebody::avatar
