// QuestSim for an application: the torque-policy pipeline (avatar/questsim.hpp) behind the front end
// the other pipelines have, so the demo, the C API and an app drive it the same way:
//   push(frame)                 any rate, any start (the user walking, sitting, ...)
//   has_output(), pose(), world(), skeleton(), joint_map(), user_scale(), contact(foot)
//   calibrate(frame), recalibrate(), set_user_scale(s), calibration_report()
//   output_time()               the user time the pose shows: NF / 36 Hz = 0.17 s behind the input
//
// Calibration. The policy observes the devices' own frames (no offsets to calibrate); the one user
// parameter is the height h that sizes the avatar and is the observation's o_user,scale (§3.6). It
// comes from features::AutoCalibration run on the pipeline's sanitised ticks: the stature of the
// user's standing windows (eye height / 0.936); until one is found, the stature of the first upright
// headset frame (the paper sizes its character from the headset; a 1.75 m default body under a
// 1.55 m user's headset crouches: the validation split's performers are 1.45-1.62 m by this rule),
// or the 1.75 m default before that; a refusal outside [1.2, 2.2] m. Whenever
// the estimate moves by more than resize_threshold (1 cm), the avatar is rescaled in place
// (QuestSimPipeline::set_user_height: no allocation) and stands again under the headset on the
// next tick; counted in resizes() and restarts(). calibrate(frame) takes one upright frame (a
// T-pose or a standing frame) instead and stops the search until recalibrate().
//
// Output. The skeleton is the avatar's own tree (its bodies, names and parents; offsets of the
// 1.75 m default avatar), so pose() / world() are the simulated bodies: world rotation R_j and
// origin p_j of body j, local rotation R_parent^T R_j, positions in that skeleton's units (divided
// by user_scale() = h / 1.75 m), as the other pipelines give theirs on the standard skeleton. A
// frame with a non-finite number keeps the last one (pose::PoseOutput). contact(foot): a contact
// of the simulator's last step on that foot or its toes carries force.
// push(), the reads and the calibration calls never allocate, throw or lock (tests/questsim/
// test_session.cpp counts); the constructor allocates everything.
#pragma once
#include <cmath>
#include <memory>

#include "sparsebody/avatar/questsim.hpp"
#include "sparsebody/features/auto_calibration.hpp"
#include "sparsebody/features/device_model.hpp"
#include "sparsebody/pose/body_proportions.hpp"
#include "sparsebody/pose/joint_map.hpp"
#include "sparsebody/pose/pose_output.hpp"
#include "sparsebody/pose/skeleton.hpp"

namespace sparsebody::avatar {

inline features::AutoCalibrationConfig questsim_calibration_defaults() noexcept {
  features::AutoCalibrationConfig c;
  c.size_from_headset_both_ways = true;  // the avatar as tall as the first upright headset frame says
  return c;
}

struct QuestSimSessionConfig {
  QuestSimConfig questsim{};
  // The standing-window search (enabled by default); before it finds one, the first upright
  // headset frame sizes the avatar, up or down (size_from_headset_both_ways).
  features::AutoCalibrationConfig calibration = questsim_calibration_defaults();
  features::DeviceModel devices{};                // where the headset sits on the head (the eye point)
  double resize_threshold = 0.01;                 // m of stature: smaller refinements keep the avatar
};

template <class S = float, class W = float>
class QuestSimSession {
 public:
  using Pipeline = QuestSimPipeline<S, W>;
  using Weights = typename Pipeline::Weights;
  using Model = typename Pipeline::Model;
  struct Meta {
    double frame_rate = 36.0;  // control ticks per second (the rate of pose())
  };
  static constexpr double kDefaultStature = character::AvatarOptions{}.height;  // the 1.75 m default avatar

  static std::shared_ptr<const Weights> load(const std::string& path) { return Pipeline::load_weights(path); }

  explicit QuestSimSession(std::shared_ptr<const Weights> weights, QuestSimSessionConfig cfg = {})
      : cfg_(cfg), pipe_(std::move(weights), kDefaultStature, cfg.questsim),
        skeleton_(skeleton_of(character::default_avatar<double, Pipeline::MB, Pipeline::MD>())),
        map_(pose::JointMap::from_names(skeleton_, "QuestSim avatar")),
        // the default stature is the avatar's: standard head height + eye offset = 0.936 x 1.75 m
        auto_(cfg.devices, kDefaultStature * cfg.calibration.eye_height_ratio - cfg.devices.eye.y(), cfg.calibration),
        trial_(std::make_unique<features::AutoCalibration>(auto_)) {
    meta_.frame_rate = cfg.questsim.control_rate;
    out_.resize(skeleton_.size());
  }

  int push(const trackers::TrackerFrame& f) noexcept {
    return pipe_.push(f, [this](const trackers::TrackerFrame& tick, bool restart) { after_tick(tick, restart); });
  }
  // The same, calling after(tick, restart) after each tick (as PipelineFrontEnd::push).
  template <class After>
  int push(const trackers::TrackerFrame& f, After&& after) noexcept {
    return pipe_.push(f, [this, &after](const trackers::TrackerFrame& tick, bool restart) {
      after_tick(tick, restart);
      after(tick, restart);
    });
  }

  // Back to the constructed state (no output, the character stands again at the next frame); the
  // calibration is kept (recalibrate() forgets it), the pipeline's counters too.
  void reset() noexcept {
    pipe_.reset();
    out_.reset();
    frames_ = 0;
    auto_.break_window();
  }

  // One upright frame (T-pose or standing, facing forward): its eye height gives the stature, the
  // search stops until recalibrate(). False (nothing changed) when the frame gives no usable height.
  bool calibrate(const trackers::TrackerFrame& frame) noexcept {
    features::AutoCalibration& trial = *trial_;  // a scratch copy: a refused frame changes nothing
    trial = auto_;
    if (!trial.calibrate_from(frame) || !pipe_.set_user_height(trial.report().stature)) return false;
    auto_ = trial;
    ++resizes_;
    return true;
  }
  // Forget the calibration and search again (the user sat down, or handed the headset on): the
  // default body until the next standing window.
  void recalibrate() noexcept {
    auto_.recalibrate();
    resize(auto_.report().stature, true);
  }
  // The application sets the size: s = standard / user (as the kinematic pipelines' scale), so the
  // stature is 1.75 m / s. The search stops until recalibrate(). False for a stature outside the
  // pipeline's height range.
  bool set_user_scale(double s) noexcept {
    if (!(s > 0) || !pipe_.set_user_height(kDefaultStature / s)) return false;
    features::Calibration c = auto_.calibration();
    c.scale = s;
    auto_.set_explicit(c, features::CalibrationSource::Application);
    ++resizes_;
    return true;
  }

  // Output.
  const pose::BodyPose& pose() const noexcept { return out_.pose(); }
  const pose::WorldPose& world() const noexcept { return out_.world(); }
  int recentres() const noexcept { return pipe_.tracker_stream().recentres(); }  // trackers/recenter.hpp
  // Controllers found in the other hands and exchanged (trackers/controller_swap.hpp; the policy
  // observes the devices' own frames, so nothing else follows).
  int controller_swaps() const noexcept { return pipe_.tracker_stream().controller_swaps(); }
  bool controllers_swapped() const noexcept { return pipe_.tracker_stream().controllers_swapped(); }
  bool has_output() const noexcept { return out_.has_output(); }
  long long frames() const noexcept { return frames_; }  // control ticks since the last reset
  double output_time() const noexcept { return pipe_.tracked_time(); }
  double delay_seconds() const noexcept { return pipe_.latency(); }
  const pose::Skeleton& skeleton() const noexcept { return skeleton_; }
  const pose::Skeleton& standard_skeleton() const noexcept { return skeleton_; }
  const pose::BodyProportions& body_proportions() const noexcept { return prop_; }  // standard (the simulated avatar's)
  void set_body_proportions(const pose::BodyProportions&) noexcept {}  // not used: the simulated avatar's are standard
  const pose::JointMap& joint_map() const noexcept { return map_; }
  double user_scale() const noexcept { return pipe_.user_height() / kDefaultStature; }
  bool contact(int foot) const noexcept {
    return pipe_.observation_builder().foot_forces(pipe_.simulator())[foot ? 1 : 0].squaredNorm() > S(0);
  }
  const Meta& meta() const noexcept { return meta_; }
  const features::CalibrationReport& calibration_report() const noexcept { return auto_.report(); }
  const features::AutoCalibration& auto_calibration() const noexcept { return auto_; }

  // Events: falls (each stood the character up again), and every restart of the character (tracker
  // resets, failed substeps, falls and resizes).
  long long falls() const noexcept { return pipe_.falls(); }
  long long resizes() const noexcept { return resizes_; }
  long long restarts() const noexcept {
    return pipe_.tracker_resets() + pipe_.simulation_failures() + pipe_.falls() + resizes_;
  }
  const Pipeline& pipeline() const noexcept { return pipe_; }
  Pipeline& pipeline() noexcept { return pipe_; }
  const QuestSimSessionConfig& config() const noexcept { return cfg_; }

 private:
  // The avatar's tree as a skeleton: names, parents, joint offsets (body origins in the parent's
  // frame; the reference pose has every joint frame aligned with the world).
  template <class M>
  static pose::Skeleton skeleton_of(const M& m) {
    pose::Skeleton s;
    for (int i = 0; i < m.nb; ++i) {
      s.names.push_back(m.names[i]);
      s.parents.push_back(m.bodies[i].parent);
      s.offsets.push_back(m.bodies[i].pos.template cast<double>());
    }
    return s;
  }

  void after_tick(const trackers::TrackerFrame& tick, bool restart) noexcept {
    const trackers::SanitizedFrame& sf = pipe_.tracker_stream().last_sanitized();
    if (restart || sf.reset) auto_.break_window();
    ++frames_;
    if (!sf.usable || !pipe_.started()) return;
    write_output();
    if (auto_.push(tick.time, sf.pose, sf.measured)) resize(auto_.report().stature, false);
  }

  void write_output() noexcept {
    const auto& d = pipe_.simulator().data();
    const double k = 1.0 / user_scale();
    pose::BodyPose& p = out_.pose();
    pose::WorldPose& w = out_.world();
    for (int j = 0; j < skeleton_.size(); ++j) {
      w.rotation[j] = Eigen::Quaterniond(d.R[j].template cast<double>()).normalized();
      w.position[j] = k * d.p[j].template cast<double>();
      const int par = skeleton_.parents[j];
      p.local[j] = par < 0 ? w.rotation[j] : (w.rotation[par].conjugate() * w.rotation[j]).normalized();
    }
    p.root_position = w.position[0];
    out_.commit();
  }

  // The avatar follows the calibration's stature when it moved by more than the threshold (or
  // always, `force`); a stature outside the pipeline's range keeps the current avatar.
  void resize(double stature, bool force) noexcept {
    if (!force && std::fabs(stature - pipe_.user_height()) <= cfg_.resize_threshold) return;
    if (std::fabs(stature - pipe_.user_height()) > 1e-9 && pipe_.set_user_height(stature)) ++resizes_;
  }

  QuestSimSessionConfig cfg_;
  Pipeline pipe_;
  pose::Skeleton skeleton_;
  pose::JointMap map_;
  pose::BodyProportions prop_{};
  features::AutoCalibration auto_;
  std::unique_ptr<features::AutoCalibration> trial_;  // calibrate()'s scratch copy
  pose::PoseOutput out_;
  Meta meta_;
  long long frames_ = 0, resizes_ = 0;
};

using QuestSimSessionDefault = QuestSimSession<>;
using QuestSimSessionF16 = QuestSimSession<float, nn::f16>;
using QuestSimSessionQ8 = QuestSimSession<float, nn::q8>;

}  // namespace sparsebody::avatar
