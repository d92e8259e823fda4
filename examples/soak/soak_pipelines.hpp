// One adapter per pipeline, the same shape for the soak loop: push(), output_finite(),
// head_distance(headset frame), calibrate_on(frame) / restore_calibration(), counters().
#pragma once
#include <cmath>
#include <memory>
#include <string>

#include "soak_checks.hpp"
#include "sparsebody/avatar/lobstr_pipeline.hpp"
#include "sparsebody/avatar/n3p_direct.hpp"
#include "sparsebody/avatar/n3p_physics.hpp"
#include "sparsebody/avatar/questsim_session.hpp"
#include "sparsebody/pose/joint_map.hpp"

namespace soak {

namespace sb = sparsebody;

inline double horizontal(const Eigen::Vector3d& a, const sb::trackers::Vec3f& b) {
  return std::hypot(a.x() - b.x, a.z() - b.z);
}

template <class World>
bool world_finite(const World& w) {
  for (std::size_t j = 0; j < w.position.size(); ++j)
    if (!w.position[j].allFinite() || !w.rotation[j].coeffs().allFinite()) return false;
  return true;
}

// The kinematic pipelines share everything but their calibration type.
template <class P, class Calib>
struct KinematicAdapter {
  P pipe;
  Calib proper;
  int head = 0;

  template <class W>
  KinematicAdapter(W&& weights, double clip_leg) : pipe(std::forward<W>(weights)) {
    const double s = sb::pose::leg_length(pipe.standard_skeleton(), pipe.joint_map()) / clip_leg;  // clips -> standard skeleton
    set_scale(proper, s);
    pipe.set_calibration(proper);
    head = pipe.joint_map()[sb::pose::Role::Head];
  }
  static void set_scale(sb::features::Calibration& c, double s) { c.scale = s; }
  static void set_scale(sb::features::n3p::N3PCalibration& c, double s) { c.base.scale = s; }

  int push(const sb::trackers::TrackerFrame& f) { return pipe.push(f); }
  bool output_finite() const { return !pipe.has_output() || world_finite(pipe.world()); }
  double head_distance(const sb::trackers::TrackerFrame& f) const {
    return pipe.has_output() ? horizontal(pipe.world().position[head] * pipe.user_scale(), f.pose[0].position) : 0.0;
  }
  void calibrate_on(const sb::trackers::TrackerFrame& f) { pipe.calibrate(f); }  // a request on an arbitrary frame
  void restore_calibration() { pipe.set_calibration(proper); }
  void counters(Report& r) const { r.max_drift_p99 = 0.5; }
};

template <class W>
struct LoBSTrAdapter : KinematicAdapter<sb::avatar::LoBSTrPipeline<float, 256, 128, W>, sb::features::Calibration> {
  using P = sb::avatar::LoBSTrPipeline<float, 256, 128, W>;
  explicit LoBSTrAdapter(double clip_leg)
      : KinematicAdapter<P, sb::features::Calibration>(P::load(SPARSEBODY_DEFAULT_WEIGHTS), clip_leg) {}
};

template <class W>
struct N3PAdapter : KinematicAdapter<sb::avatar::N3PPipeline<float, 64, 128, 128, W>, sb::features::n3p::N3PCalibration> {
  using P = sb::avatar::N3PPipeline<float, 64, 128, 128, W>;
  explicit N3PAdapter(double clip_leg)
      : KinematicAdapter<P, sb::features::n3p::N3PCalibration>(P::load(SPARSEBODY_DEFAULT_N3P_WEIGHTS), clip_leg) {}
};

template <class W>
struct N3PPhysicsAdapter
    : KinematicAdapter<sb::avatar::N3PPhysicsPipeline<float, 64, 128, 128, float, 24, 72, W>, sb::features::n3p::N3PCalibration> {
  using P = sb::avatar::N3PPhysicsPipeline<float, 64, 128, 128, float, 24, 72, W>;
  explicit N3PPhysicsAdapter(double clip_leg)
      : KinematicAdapter<P, sb::features::n3p::N3PCalibration>(P::load(SPARSEBODY_DEFAULT_N3P_PHYSICS_WEIGHTS), clip_leg) {}
  void counters(Report& r) const {
    r.max_drift_p99 = 1.0;  // the output is 0.1 s behind the input, and falls reset the character
    r.falls = this->pipe.falls();
    r.resets = this->pipe.restarts();
    r.sim_failures = this->pipe.sim_failures();
  }
};

// QuestSim through its session (what the demo and the C API run): the avatar sized by the automatic
// calibration, resized on a calibration request; its head body against the headset.
template <class W>
struct QuestSimAdapter {
  using P = sb::avatar::QuestSimSession<float, W>;
  std::unique_ptr<P> pipe;
  int head = 0;

  explicit QuestSimAdapter(const std::string& policy) {
    pipe = std::make_unique<P>(P::load(policy));
    head = pipe->joint_map()[sb::pose::Role::Head];
  }
  int push(const sb::trackers::TrackerFrame& f) { return pipe->push(f); }
  bool output_finite() const {
    const auto& sim = pipe->pipeline().simulator();
    return sim.q().allFinite() && sim.v().allFinite() && (!pipe->has_output() || world_finite(pipe->world()));
  }
  double head_distance(const sb::trackers::TrackerFrame& f) const {
    return pipe->has_output() ? horizontal(pipe->world().position[head] * pipe->user_scale(), f.pose[0].position) : 0.0;
  }
  void calibrate_on(const sb::trackers::TrackerFrame& f) { pipe->calibrate(f); }  // a request on an arbitrary frame
  void restore_calibration() { pipe->recalibrate(); }  // back to the automatic search
  void counters(Report& r) const {
    r.max_drift_p99 = -1;  // the shipped policy still falls ~33 times a minute: drift is reported only
    const auto& q = pipe->pipeline();
    r.falls = q.falls();
    r.resets = q.tracker_resets() + pipe->resizes();
    r.sim_failures = q.simulation_failures();
  }
};

}  // namespace soak
