// QuestSim torque-policy tracking (Winkler et al., SIGGRAPH Asia 2022, §3, Appendix A): headset and
// two controllers in, a simulated full-body avatar out.
//
//   TrackerFrame (any rate) -> Resampler (36 Hz) -> TrackerSanitizer (bad input)
//     -> window of sensor frames t .. t+NF (a shift register, NF = 6)
//     -> observation o (questsim_observation.hpp) -> policy pi: MLP [400, 300, 200], tanh
//     -> a in [-1, 1]^NJ, tau_j = tau_max,j * a_j on every non-root DoF (direct torques, no PD;
//        control/questsim_actuation.hpp: per-joint limits, or the paper's 200 N m everywhere)
//     -> 2 simulation substeps of 1/72 s (Simulator in ControlMode::Torque).
//
// Latency (§3.5): the policy acting for user time t observes frames up to t + NF, so it can only run
// once frame t + NF has arrived. The character therefore tracks the user NF control periods late:
// NF / 36 Hz = 6 / 36 s = 166.7 ms (the paper's "160 ms"). latency() returns it, tracked_time() the
// user time the character currently corresponds to (newest tick time - latency()).
// Start-up: the window is filled with the first usable frame, so control starts immediately, as if
// the user had stood still for NF frames before.
//
// Avatar scale (§3.6): the avatar is character::avatar_for_user_height(h) (lengths x h/1.75, masses x
// (h/1.75)^3, inertias x (h/1.75)^5), h the user's height estimated by user_height_from_headset() from a
// frame where the user stands upright: h = headset height / eye_height_ratio (0.936: eye height over
// stature, Drillis & Contini 1966). The same h is the observation's o_user,scale. set_user_height(h)
// rescales the avatar in place (no allocation) and stands it again under the headset.
// This class has no calibration inside push(): it has no offsets to calibrate (the policy observes
// the devices' own frames, as its training did), and the one user parameter is h. The session
// front end (avatar/questsim_session.hpp) adds what the other pipelines have: the automatic
// calibration of the stature from standing windows, recalibrate(), and the output as a pose on
// the avatar's skeleton; the demo and the C API run it. Here: give h (or from_calibration_report).
// Joint "friction of 0.1" (Appendix A) is a passive viscous damping of 0.1 N m s/rad on every joint,
// integrated implicitly by the simulator. Floor friction is the simulator's default mu = 1.0.
//
// Recovery (each is reported by tick()/control_step() and counted):
//   - bad tracker input (trackers/sanitizer.hpp): NaN/Inf, a non-unit quaternion, an invalid flag or
//     a jump > 1 m in one tick make a device invalid for that tick and its last good pose is held;
//     before the first valid headset frame nothing is simulated (Waiting); a long headset loss
//     (> 0.5 s) or a tracking-origin jump (a jump confirmed 3 ticks in a row) -> TrackerReset: the
//     window is refilled with the current frame and the character stands again under the headset
//     (during a long loss this repeats every tick, i.e. the character is held standing under the
//     last headset pose until the headset returns; tracking then resumes without a further reset);
//     frames with a non-finite time are dropped and a time gap > 0.25 s restarts (Resampler);
//   - non-finite observation (cannot happen with finite state and sanitised input; guarded anyway)
//     or non-finite policy output -> RejectedAction: zero torques for this step;
//   - a substep that fails (StepStatus != Ok: the simulator has already rolled the state back)
//     -> SimulationFailure: the character is reset to standing under the headset of frame t;
//   - a fall: root (Hips) height below fall_height_ratio x its standing height, or the root's up axis
//     tilted beyond fall_tilt -> Fall: same reset. (The paper describes no run-time recovery; this
//     is ours.)
// Nothing non-finite ever leaves a step: the state is the simulator's (its step never stores a
// non-finite number, and a state corrupted from outside is reset as above), torques are finite by
// construction, and a rejected observation is zeroed.
// Templates: S = simulation scalar (float or double); W = policy weight storage: float, nn::f16
// (half the bytes) or nn::q8 (int8, approximate: nn/int8.hpp); the policy computes in float. tick(), push() and control_step() never
// allocate, throw or lock; the constructor allocates everything once.
//
// Use:
//   auto w = avatar::QuestSimDefault::load_weights("questsim_policy.json");   // kind "questsim_policy"
//   auto c = avatar::QuestSimDefault::from_standing_frame(w, standing_frame);    // nullptr if no height
//   // or: avatar::QuestSimDefault c(w, avatar::user_height_from_headset(standing_frame));
//   for (frame : frames) c->push(frame);           // any rate; runs one control step per 36 Hz tick
//   c->simulator().data().R[i], .p[i]              // the avatar's body poses (world = stage space)
//   c->tracked_time()                               // the user time those poses correspond to
#pragma once
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include "sparsebody/avatar/questsim_config.hpp"
#include "sparsebody/avatar/questsim_event.hpp"
#include "sparsebody/character/avatar.hpp"
#include "sparsebody/control/fall_detector.hpp"
#include "sparsebody/control/questsim_actuation.hpp"
#include "sparsebody/control/questsim_observation.hpp"
#include "sparsebody/control/questsim_standing.hpp"
#include "sparsebody/features/calibration_report.hpp"
#include "sparsebody/networks/policy_nets.hpp"
#include "sparsebody/nn/half.hpp"
#include "sparsebody/nn/int8.hpp"
#include "sparsebody/nn/network.hpp"
#include "sparsebody/trackers/tracker_stream.hpp"

namespace sparsebody::avatar {

// S: simulation scalar; W: the policy's weight storage (float, or nn::f16); NF future frames;
// NB / NJ: the avatar's bodies and non-root DoFs (the default avatar's unless a custom one is given).
template <class S = float, class W = float, int NF = 6, int NB = character::kDefaultAvatarBodies, int NJ = character::kDefaultAvatarJointDofs>
class QuestSimPipeline {
 public:
  static constexpr int MB = 24, MD = 72;  // bounds of character::default_avatar
  using Model = dynamics::Model<S, MB, MD>;
  using Sim = dynamics::Simulator<S, MB, MD>;
  using Builder = control::QuestSimObservationBuilder<S, MB, MD, NB, NJ, NF>;
  using Layout = typename Builder::Layout;
  static constexpr int kObservationSize = Layout::size;
  static constexpr int kActionSize = NJ;
  using Net = networks::QuestSimPolicyNet<float, kObservationSize, NJ, W>;
  using Weights = nn::NetworkWeights<Net>;
  using Window = typename Builder::UserWindow;

  static std::shared_ptr<const Weights> load_weights(const std::string& path) {
    return Weights::load(path, networks::kQuestSimPolicyKind);
  }

  // Avatar scaled to `user_height` (m). Throws std::invalid_argument for a non-finite or
  // non-positive height, or when the avatar does not have NB bodies / NJ + 6 DoFs.
  QuestSimPipeline(std::shared_ptr<const Weights> weights, double user_height, QuestSimConfig cfg = {},
                     character::AvatarOptions avatar = {})
      : QuestSimPipeline(std::move(weights), scaled_avatar(user_height, cfg, avatar), user_height, cfg) {}

  // The avatar for the user standing upright in `standing` (user_height_from_headset); nullptr when
  // that frame gives no usable height (headset invalid, non-finite, or outside the height range).
  static std::unique_ptr<QuestSimPipeline> from_standing_frame(std::shared_ptr<const Weights> weights,
                                                               const trackers::TrackerFrame& standing,
                                                               QuestSimConfig cfg = {}) {
    const double h = user_height_from_headset(standing, cfg);
    if (std::isnan(h)) return nullptr;
    return std::make_unique<QuestSimPipeline>(std::move(weights), h, cfg);
  }

  // The avatar for the stature an automatic calibration found (features/auto_calibration.hpp);
  // nullptr unless the report is Calibrated.
  static std::unique_ptr<QuestSimPipeline> from_calibration_report(std::shared_ptr<const Weights> weights,
                                                                   const features::CalibrationReport& report,
                                                                   QuestSimConfig cfg = {}) {
    if (report.status != features::CalibrationStatus::Calibrated || !(report.stature > 0)) return nullptr;
    return std::make_unique<QuestSimPipeline>(std::move(weights), report.stature, cfg);
  }

  // A custom model (already at the user's scale; its joint damping and armature are used as given).
  QuestSimPipeline(std::shared_ptr<const Weights> weights, const Model& model, double user_height, QuestSimConfig cfg)
      : cfg_(cfg), height_(S(user_height)), base_height_(user_height), sim_(std::make_unique<Sim>(model)),
        base_model_(std::make_unique<Model>(model)), scaled_model_(std::make_unique<Model>(model)), obs_builder_(model),
        policy_(std::move(weights)), stream_(cfg.control_rate, cfg.sanitizer, cfg.max_gap) {
    if (!(cfg.substeps >= 1) || !(cfg.control_rate > 0))
      throw std::invalid_argument("QuestSimPipeline: substeps >= 1 and control_rate > 0 required");
    if (!(std::isfinite(user_height) && user_height > 0)) throw std::invalid_argument("QuestSimPipeline: user height must be > 0");
    sim_->options.mode = dynamics::ControlMode::Torque;
    h_ = S(1.0 / (cfg.control_rate * cfg.substeps));
    zero_v_ = Sim::VecV::Zero(model.nv);
    tau_ = zero_v_;
    size_to(model, user_height);
    obs_.fill(0.f);
    action_.fill(0.f);
  }

  // Another user (or a better estimate of this one): the avatar is rescaled to `user_height` (m) in
  // place (character::scale_model_into from the constructed model: lengths, masses, inertias and
  // torque limits as the constructor would make them) and the character stands again under the
  // next frame's headset, as after reset() (the input stream and the counters carry on). No
  // allocation. False (nothing changed) for a height outside [cfg.min_height, cfg.max_height] or
  // not finite.
  bool set_user_height(double user_height) noexcept {
    if (!(user_height >= cfg_.min_height && user_height <= cfg_.max_height)) return false;
    if (!character::scale_model_into(*base_model_, S(user_height / base_height_), *scaled_model_)) return false;
    if (!sim_->set_model_parameters(*scaled_model_)) return false;
    size_to(*scaled_model_, user_height);
    started_ = false;
    return true;
  }

  // Control period and the latency of the future frames (NF control periods).
  double control_period() const noexcept { return 1.0 / cfg_.control_rate; }
  double latency() const noexcept { return NF / cfg_.control_rate; }
  double user_height() const noexcept { return double(height_); }

  // Any-rate input: resampled to the control rate; one tick (and control step) per 36 Hz sample.
  // Returns the number of ticks run.
  int push(const trackers::TrackerFrame& f) noexcept {
    return stream_.push(f, [this](const trackers::TrackerFrame& t, bool reset) { tick(t, reset); });
  }

  // The same, calling after(tick, restart) after each tick (the session front end: calibration and
  // the output pose on the ticks this one runs).
  template <class After>
  int push(const trackers::TrackerFrame& f, After&& after) noexcept {
    return stream_.push(f, [this, &after](const trackers::TrackerFrame& t, bool reset) {
      tick(t, reset);
      after(t, reset);
    });
  }
  // The resampler and sanitizer (last_sanitized(): the last tick's devices).
  const trackers::TrackerStream& tracker_stream() const noexcept { return stream_; }
  // Trackers in the body convention (a mocap clip's joints, facing +Z) instead of OpenXR devices
  // (facing -Z): the policy reads them as they are, but the stream's controller-swap check takes
  // its heading from the headset's orientation (trackers/controller_swap.hpp).
  void set_body_convention(bool on) noexcept {
    stream_.set_head_offset(on ? Eigen::Quaterniond::Identity() : trackers::ControllerSwapDetector::openxr_head_offset());
  }

  // Back to the constructed state: no input seen, the next frame stands the character under the
  // headset (the counters of falls, resets and failures are kept: they describe the session).
  void reset() noexcept {
    stream_.reset();
    started_ = false;
  }

  // One control tick from a frame already at the control rate (time = this tick's user time).
  QuestSimEvent tick(const trackers::TrackerFrame& f, bool restart = false) noexcept {
    const trackers::SanitizedFrame& sf = stream_.sanitize(f);  // dt = the control period
    if (!sf.usable) return last_event_ = QuestSimEvent::Waiting;
    control::QuestSimSensorFrame<S> frame;
    for (int dev = 0; dev < 3; ++dev) {
      frame[dev].position = sf.pose[dev].position.template cast<S>();
      frame[dev].rotation = sf.pose[dev].orientation.toRotationMatrix().template cast<S>();
    }
    const bool reset = !started_ || restart || sf.reset;
    if (reset) {
      window_.fill(frame);
      times_.fill(f.time);
      stand_under_headset(frame);
      if (started_) ++tracker_resets_;
    } else {
      for (int k = 0; k < NF; ++k) { window_[k] = window_[k + 1]; times_[k] = times_[k + 1]; }
      window_[NF] = frame;
      times_[NF] = f.time;
    }
    const bool was_started = started_;
    started_ = true;
    const QuestSimEvent e = control_step();
    if (reset && was_started && e == QuestSimEvent::Stepped) return last_event_ = QuestSimEvent::TrackerReset;
    return e;
  }

  // The control step on the current window: observation, policy, torques, substeps, fall check.
  QuestSimEvent control_step() noexcept {
    QuestSimEvent e = QuestSimEvent::Stepped;
    obs_builder_.build(*sim_, window_, height_, obs_.data());
    bool finite = true;
    for (float x : obs_) finite &= static_cast<bool>(std::isfinite(x));
    if (finite && policy_.step_guarded(obs_.data()) == nn::NetStatus::Ok) {
      const float* a = policy_.output().data();
      for (int k = 0; k < NJ; ++k) action_[k] = std::fmin(1.f, std::fmax(-1.f, a[k]));
    } else {
      if (!finite) obs_.fill(0.f);  // never expose a non-finite observation
      action_.fill(0.f);
      e = QuestSimEvent::RejectedAction;
      ++rejected_actions_;
    }
    // tau = 200 N m * a on the non-root DoFs; the root is unactuated (no residual forces).
    for (int k = 0; k < NJ; ++k) tau_(6 + k) = tau_max_(6 + k) * S(action_[k]);
    sim_->torques() = tau_;
    last_sim_status_ = dynamics::StepStatus::Ok;
    for (int s = 0; s < cfg_.substeps; ++s) {
      const dynamics::StepStatus st = sim_->step(h_);
      if (st != dynamics::StepStatus::Ok) {
        last_sim_status_ = st;
        ++simulation_failures_;
        stand_under_headset(window_[0]);
        return last_event_ = QuestSimEvent::SimulationFailure;
      }
    }
    if (fallen()) {
      ++falls_;
      stand_under_headset(window_[0]);
      return last_event_ = QuestSimEvent::Fall;
    }
    ++steps_;
    return last_event_ = e;
  }

  // Loss of balance: root below fall_height_ratio of its standing height, or tilted beyond fall_tilt.
  bool fallen() const noexcept {
    const auto& d = sim_->data();
    return fall_.posture(d.p[0], d.R[0].col(1)) != control::FallReason::None;
  }

  // The fall rule above as a reference-free FallDetector: min_height = fall_height_ratio x the
  // standing root height (the product in S), max_tilt = fall_tilt; no drop or divergence rule.
  static control::FallDetectorConfig fall_detector_config(const QuestSimConfig& cfg, S standing_root_y) noexcept {
    control::FallDetectorConfig f;
    f.min_height = double(S(cfg.fall_height_ratio) * standing_root_y);
    f.max_tilt = cfg.fall_tilt;
    f.max_drop = f.max_error = std::numeric_limits<double>::infinity();
    return f;
  }

  // The character standing in its reference pose under the headset of `frame`, facing the
  // headset's heading (OpenXR: the device looks along its -Z), at rest. Used at start and by resets.
  void stand_under_headset(const control::QuestSimSensorFrame<S>& frame) noexcept {
    typename Sim::VecQ q = standing_q_;
    control::questsim_stand_under_headset(frame, q);
    sim_->set_state(q, zero_v_);
    tau_.setZero();
    sim_->torques() = tau_;
    policy_.reset();
  }

  // Access.
  const Sim& simulator() const noexcept { return *sim_; }
  Sim& simulator() noexcept { return *sim_; }   // e.g. to change contact parameters or the environment
  // The policy input of the last step (zeros if it was rejected as non-finite).
  const std::array<float, kObservationSize>& observation() const noexcept { return obs_; }
  const std::array<float, NJ>& action() const noexcept { return action_; }  // policy output in [-1, 1]
  const typename Sim::VecV& torques() const noexcept { return tau_; }       // applied (N m), root entries 0
  const typename Sim::VecV& torque_limits() const noexcept { return tau_max_; }  // tau_max per DoF (N m)
  const Window& window() const noexcept { return window_; }
  const Builder& observation_builder() const noexcept { return obs_builder_; }
  const nn::Network<Net>& policy() const noexcept { return policy_; }
  bool started() const noexcept { return started_; }
  double tracked_time() const noexcept { return times_[0]; }   // user time the character tracks
  double newest_time() const noexcept { return times_[NF]; }
  QuestSimEvent last_event() const noexcept { return last_event_; }
  dynamics::StepStatus last_sim_status() const noexcept { return last_sim_status_; }
  long long steps() const noexcept { return steps_; }
  long long falls() const noexcept { return falls_; }
  long long simulation_failures() const noexcept { return simulation_failures_; }
  long long tracker_resets() const noexcept { return tracker_resets_; }
  long long rejected_actions() const noexcept { return rejected_actions_; }
  const QuestSimConfig& config() const noexcept { return cfg_; }

 private:
  static Model scaled_avatar(double h, const QuestSimConfig& cfg, character::AvatarOptions o) {
    if (!(std::isfinite(h) && h > 0)) throw std::invalid_argument("QuestSimPipeline: user height must be > 0");
    Model m = character::avatar_for_user_height<S, MB, MD>(h, o);
    control::set_questsim_joints(m, cfg.joint_damping, cfg.joint_armature);
    return m;
  }

  // The avatar's user-size-dependent parts: standing pose, fall threshold, torque limits.
  void size_to(const Model& m, double user_height) noexcept {
    height_ = S(user_height);
    standing_q_ = m.neutral_configuration();
    fall_ = control::FallDetector<S>(fall_detector_config(cfg_, standing_q_(1)));
    tau_max_ = control::questsim_torque_limits(m, user_height / character::AvatarOptions{}.height,
                                               cfg_.per_joint_torque_limits ? 0.0 : cfg_.torque_scale);
    tau_.setZero();
    sim_->torques().setZero();
  }

  QuestSimConfig cfg_;
  S height_;
  double base_height_;  // the user height of the constructed model (set_user_height scales from it)
  S h_ = S(1.0 / 72);
  std::unique_ptr<Sim> sim_;
  std::unique_ptr<Model> base_model_, scaled_model_;  // the constructed avatar; set_user_height's scaling of it
  Builder obs_builder_;
  nn::Network<Net> policy_;
  trackers::TrackerStream stream_;  // the pipelines' shared front end: resampler + sanitizer
  Window window_{};
  std::array<double, NF + 1> times_{};
  alignas(64) std::array<float, kObservationSize> obs_{};
  std::array<float, NJ> action_{};
  typename Sim::VecQ standing_q_;
  typename Sim::VecV zero_v_, tau_, tau_max_;
  control::FallDetector<S> fall_;
  bool started_ = false;
  QuestSimEvent last_event_ = QuestSimEvent::Waiting;
  dynamics::StepStatus last_sim_status_ = dynamics::StepStatus::Ok;
  long long steps_ = 0, falls_ = 0, simulation_failures_ = 0, tracker_resets_ = 0, rejected_actions_ = 0;
};

// The shipped configurations on the default avatar: float simulation with float, f16 or int8
// policy weights, and a double-precision simulation.
using QuestSimDefault = QuestSimPipeline<>;
using QuestSimF16 = QuestSimPipeline<float, nn::f16>;
using QuestSimQ8 = QuestSimPipeline<float, nn::q8>;
using QuestSimDouble = QuestSimPipeline<double>;

}  // namespace sparsebody::avatar
