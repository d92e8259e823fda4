// Batched training environment for the QuestSim torque policy (Winkler et al. 2022, §3, App. A):
// N simulated characters stepped per call, each tracking its own reference clip. The run-time
// pipeline's pieces, unchanged: the same avatar model (character::avatar_for_user_height, joint
// damping 0.1, armature 0.05 kg m^2), the same Simulator in torque mode at 2 substeps of 1/72 s, the same observation
// builder (control/questsim_observation.hpp) and the same action mapping (tau = tau_max x
// clamp(a, -1, 1) on every non-root DoF, control/questsim_actuation.hpp), so a policy trained here
// behaves the same in avatar::QuestSimPipeline.
//
// Per character and control step t -> t+1:
//   o_t = obs(sim state, sensor frames t .. t+NF of the clip, user height)   (written before)
//   a_t -> torques -> 2 substeps -> reward r_t against s_gt,t+1 (training/questsim_reward.hpp)
//   termination: fall (root below 0.5 x standing height or tilted > 1.2 rad, the pipeline's rule),
//     head farther than max_head_error from the reference head, or a failed substep;
//   truncation: the clip ends (t + NF + 1 past its last frame) or max_episode_steps.
//   Ended characters restart at once by reference-state initialisation (Peng et al. 2018): a clip
//   drawn with probability ~ its length, a frame uniform in it, the simulator set to the retargeted
//   reference pose and finite-difference velocity. The observation returned for them is the new
//   episode's; final_observation() keeps the ended one's (for bootstrapping truncated episodes).
// Residual force (optional, for a curriculum): the simulator's root servo pulling the root towards
// the reference root with the bound max_force / max_torque; 0 disables it. Train with it annealed
// to zero and measure with it off.
// Expert actions (for imitation warm starts, DAgger): what a privileged tracker that sees the
// reference would do, for every character's current state: computed-torque control,
// qdd* = [a_ref] + wn^2 (q_target (-) q) + 2 wn (v_ref - v) (wn = expert_wn; q_target frame t+1 with
// expert_lead, else t; a_ref with expert_feedforward), tau = RNEA(q, v, qdd*) on the non-root DoFs,
// a = clamp(tau / tau_max). Plain RNEA of the floating body carries no body weight through the legs;
// expert_support (stance_support) asks the root's wrench from the feet near the floor instead.
// Measured (40 training clips of the default motions, 64 characters, 600 steps, expert only):
// - no residual: episodes of 3.8 control steps (0.1 s) plain, ~10 with stance support;
// - 300 N / 100 N m residual, wn 8: 11.9 steps plain, 23.0 with stance support (falls 2564 -> 472,
//   but failed substeps 153 -> 721); on 3 validation clips the support did worse (453 against 229
//   terminations): not robust;
// - 1000 N / 300 N m residual: mean reward 0.47 against 0.31 for zero torques.
// So neither is yet a teacher that stands by itself; DAgger on it (run 2, 2026-12-02) only declined.
// Restarts lift the episode's reference so that no contact point starts inside the floor (the
// retargeted avatar's feet sat up to 2 cm deep and launched it).
// Determinism: every character has its own random stream seeded from (seed, index), so results do
// not depend on the thread count. The constructor allocates everything; step() with threads = 1
// allocates nothing (threads > 1 starts std::threads for the call, which does).
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <thread>
#include <vector>

#include "sparsebody/character/avatar.hpp"
#include "sparsebody/control/n3p_sim_retarget.hpp"
#include "sparsebody/control/questsim_actuation.hpp"
#include "sparsebody/control/questsim_observation.hpp"
#include "sparsebody/control/questsim_standing.hpp"
#include "sparsebody/dynamics/rnea.hpp"
#include "sparsebody/dynamics/simulator.hpp"
#include "sparsebody/predict/n3p_meta.hpp"
#include "sparsebody/training/questsim_reference.hpp"
#include "sparsebody/training/questsim_reward.hpp"

namespace sparsebody::training {

struct QuestSimEnvConfig {
  double control_rate = 36.0;     // Hz (Appendix A)
  int substeps = 2;
  bool per_joint_torque_limits = true;  // as QuestSimConfig (control/questsim_actuation.hpp)
  double torque_scale = 200.0;    // N m per unit action when !per_joint_torque_limits
  double joint_damping = 0.1;     // N m s/rad
  double joint_armature = 0.05;   // kg m^2 per joint DoF, as QuestSimConfig (dynamics::Body::armature)
  double fall_height_ratio = 0.5, fall_tilt = 1.2;  // the pipeline's fall rule (QuestSimConfig)
  double max_head_error = 0.5;    // m: early termination (tracking lost)
  int max_episode_steps = 300;    // control steps (8.3 s)
  // Share of episodes that start where the run-time pipeline resets the character: the neutral pose
  // at rest under the reference's headset (control/questsim_standing.hpp), instead of the reference
  // state. Without them the policy never sees the pose it restarts from after a fall.
  double neutral_start = 0.0;
  double residual_max_force = 0;  // N: root servo bound (0: off)
  double residual_max_torque = 0; // N m
  double residual_kp = 2000, residual_kd = 200, residual_kp_rot = 400, residual_kd_rot = 40;
  bool expert = false;            // compute expert_actions() (one RNEA per character and step)
  double expert_wn = 15;          // rad/s: natural frequency of the expert's tracking
  bool expert_lead = true;        // qdd*'s position term towards frame t+1 (else t)
  bool expert_support = false;    // the feet carry the root's wrench (stance_support below)
  double expert_friction = 0.8, expert_cop_radius = 0.06, expert_yaw_radius = 0.03;  // -, m, m
  bool expert_feedforward = false;  // add the reference's acceleration a_ref to qdd*
  double expert_support_height = 0.02;  // m: a foot with a contact point this low is a support
  // Nonzero: the expert is a plain PD servo to the reference instead, a = kp (q_target (-) q) + kd (v_ref - v)
  // in units of each joint's torque limit (1/rad, s/rad): a diagnostic of what bounded torques can hold.
  double expert_pd_kp = 0, expert_pd_kd = 0;
  // Also write reference_observations() and frames() every step: what a learned world model and a
  // policy trained through it (SuperTrack, Fussell et al. 2021) need. Off on the PPO path.
  bool record_reference = false;
  QuestSimRewardConfig reward{};
};

template <int NF = 6>
class QuestSimEnv {
 public:
  using S = float;
  static constexpr int MB = 24, MD = 72;
  static constexpr int NB = character::kDefaultAvatarBodies, NJ = character::kDefaultAvatarJointDofs;
  using Model = dynamics::Model<S, MB, MD>;
  using Sim = dynamics::Simulator<S, MB, MD>;
  using Data = dynamics::Data<S, MB, MD>;
  using VecQ = typename Model::VecQ;
  using VecV = typename Model::VecV;
  using Builder = control::QuestSimObservationBuilder<S, MB, MD, NB, NJ, NF>;
  using Retarget = control::N3PSimRetarget<S, MB, MD>;
  static constexpr int kObservationSize = Builder::Layout::size;
  static constexpr int kActionSize = NJ;

  // One character per entry of `heights` (m: the avatar is scaled to it and it is the observed
  // o_user,scale). `clips`: reference motions in the standard skeleton of `meta`.
  QuestSimEnv(std::shared_ptr<const std::vector<QuestSimReference>> clips, const predict::N3PMeta& meta,
              const std::vector<double>& heights, unsigned long long seed, QuestSimEnvConfig cfg = {})
      : cfg_(cfg), clips_(std::move(clips)) {
    if (!clips_ || clips_->empty()) throw std::invalid_argument("QuestSimEnv: no reference clips");
    if (heights.empty()) throw std::invalid_argument("QuestSimEnv: no characters");
    for (const auto& c : *clips_) {
      const int usable = c.frames() - NF - 2;
      cum_.push_back((cum_.empty() ? 0.0 : cum_.back()) + std::max(0, usable));
    }
    if (!(cum_.back() > 0)) throw std::invalid_argument("QuestSimEnv: every clip is shorter than the observation window");
    h_ = S(1.0 / (cfg.control_rate * cfg.substeps));
    for (std::size_t i = 0; i < heights.size(); ++i) {
      if (!(heights[i] > 0.5 && heights[i] < 3.0)) throw std::invalid_argument("QuestSimEnv: height out of range");
      chars_.push_back(std::make_unique<Character>(meta, heights[i], cfg, seed, i));
    }
    const int n = size();
    obs_.assign(std::size_t(n) * kObservationSize, 0.f);
    final_obs_.assign(std::size_t(n) * kObservationSize, 0.f);
    reward_.assign(std::size_t(n), 0.f);
    terms_.assign(std::size_t(n) * 5, 0.f);
    expert_.assign(std::size_t(n) * kActionSize, 0.f);
    terminated_.assign(std::size_t(n), 0);
    truncated_.assign(std::size_t(n), 0);
    ref_obs_.assign(std::size_t(n) * kObservationSize, 0.f);
    frames_.assign(std::size_t(n) * kFrameSize, 0.f);
    final_frames_.assign(std::size_t(n) * kFrameSize, 0.f);
    for (int i = 0; i < n; ++i) {
      restart(i);
      write_observation(i, obs_.data() + std::size_t(i) * kObservationSize);
      write_expert(i);
    }
  }

  int size() const noexcept { return static_cast<int>(chars_.size()); }
  // frames(): per character the floor heading frame S of the simulated state, then of the reference
  // state: (cos theta, sin theta, origin x, origin z) each (QuestSimFloorFrame).
  static constexpr int kFrameSize = 8;

  // Restart every character (new reference-state initialisations from their random streams).
  void reset_all() noexcept {
    for (int i = 0; i < size(); ++i) {
      restart(i);
      write_observation(i, obs_.data() + std::size_t(i) * kObservationSize);
      write_expert(i);
    }
  }

  // actions: size() x kActionSize, row-major, values clamped to [-1, 1] (non-finite -> 0).
  // threads: 1 = this thread only; k > 1 splits the characters into k contiguous blocks.
  void step(const float* actions, int threads = 1) {
    const int n = size();
    threads = std::max(1, std::min(threads, n));
    if (threads == 1) {
      step_range(actions, 0, n);
      return;
    }
    std::array<std::thread, 64> pool;
    threads = std::min(threads, 64);
    for (int k = 1; k < threads; ++k)
      pool[k] = std::thread([this, actions, k, threads, n] { step_range(actions, n * k / threads, n * (k + 1) / threads); });
    step_range(actions, 0, n / threads);
    for (int k = 1; k < threads; ++k) pool[k].join();
  }

  void set_residual(double max_force, double max_torque) noexcept {
    cfg_.residual_max_force = max_force;
    cfg_.residual_max_torque = max_torque;
  }
  const QuestSimEnvConfig& config() const noexcept { return cfg_; }

  float* observations() noexcept { return obs_.data(); }
  const float* final_observations() const noexcept { return final_obs_.data(); }
  const float* rewards() const noexcept { return reward_.data(); }
  const float* reward_terms() const noexcept { return terms_.data(); }
  // The norm of the root wrench the expert's inverse dynamics asks for (n, f in root coordinates,
  // N m and N mixed as in RNEA's root rows) and what is left of it after the stance support (equal
  // when there is none): the contact limits decide how much the feet can take.
  std::array<double, 2> expert_root_wrench(int i) const noexcept {
    return {double(chars_[i]->root_need), double(chars_[i]->root_left)};
  }
  const float* expert_actions() const noexcept { return expert_.data(); }
  // With config().record_reference (else zeros): the reference state s_gt at frame(i) as an
  // observation of the same layout (its own heading frame, foot forces 0, the same user window),
  // the heading frames of the current state (kFrameSize per character, see above) and of the
  // final state of an episode that ended this step (first 4 values).
  const float* reference_observations() const noexcept { return ref_obs_.data(); }
  const float* frames() const noexcept { return frames_.data(); }
  const float* final_frames() const noexcept { return final_frames_.data(); }  // n x kActionSize, see above (zeros unless config().expert)  // n x 5: r(q), r(qd), r(x), r(xd), r_f
  // Why each character's episode ended this step: 0 it did not, 1 a failed substep, 2 a fall,
  // 3 head farther than max_head_error from the reference, 4 a non-finite reward.
  const unsigned char* terminated() const noexcept { return terminated_.data(); }
  const unsigned char* truncated() const noexcept { return truncated_.data(); }
  // Per character: clip index, frame index of the current state, episode step.
  int clip(int i) const noexcept { return chars_[i]->clip; }
  int frame(int i) const noexcept { return chars_[i]->t; }
  int episode_step(int i) const noexcept { return chars_[i]->steps; }
  double root_residual_force(int i) const noexcept { return double(chars_[i]->sim.root_servo_force().norm()); }
  const Sim& simulator(int i) const noexcept { return chars_[i]->sim; }
  const VecQ& reference_q(int i) const noexcept { return chars_[i]->q_ref; }  // s_gt at frame(i), retargeted
  const Model& model(int i) const noexcept { return chars_[i]->model; }
  double height(int i) const noexcept { return double(chars_[i]->height); }
  // The sensor frame (0 headset, 1 left, 2 right) the character's current state corresponds to.
  const control::QuestSimSensorFrame<double>& sensor(int i) const noexcept {
    return (*clips_)[chars_[i]->clip].sensor[chars_[i]->t];
  }

 private:
  struct Character {
    Model model;
    Sim sim;
    Builder builder;
    Retarget retarget;
    Data ref, scratch;
    VecQ q_ref, q_next, q_after;
    VecQ q_neutral;  // the model's neutral configuration (neutral starts)
    VecV v_ref, v_after, tau, zero_v, tau_max, err, qdd, tau_exp;
    typename Builder::UserWindow window{};
    std::mt19937_64 rng;
    S height;
    S standing_root_y = 1;
    S lift = 0;  // m added to the reference root height this episode (restart)
    S root_need = 0, root_left = 0;  // |root rows| of the expert's RNEA before / after stance support
    std::array<double, 2> fy_prev{};
    int clip = 0, t = 0, steps = 0;
    int head = 0;  // the Head body

    Character(const predict::N3PMeta& meta, double h, const QuestSimEnvConfig& cfg, unsigned long long seed, std::size_t index)
        : model(make_model(h, cfg)), sim(model), builder(model), retarget(Retarget::from_meta(model, meta)), ref(model), scratch(model),
          rng(seed * 0x9E3779B97F4A7C15ull + index + 1), height(S(h)) {
      sim.options.mode = dynamics::ControlMode::Torque;
      q_ref = q_next = q_neutral = model.neutral_configuration();
      q_after = q_ref;
      v_ref = v_after = tau = zero_v = err = qdd = tau_exp = VecV::Zero(model.nv);
      standing_root_y = q_ref(1);
      tau_max = control::questsim_torque_limits(model, h / character::AvatarOptions{}.height,
                                                cfg.per_joint_torque_limits ? 0.0 : cfg.torque_scale);
      head = model.find("Head");
      if (head < 0) throw std::invalid_argument("QuestSimEnv: the avatar has no Head body");
    }
    static Model make_model(double h, const QuestSimEnvConfig& cfg) {
      Model m = character::avatar_for_user_height<S, MB, MD>(h);
      control::set_questsim_joints(m, cfg.joint_damping, cfg.joint_armature);
      return m;
    }
  };

  // Reference configuration and velocity at frame t of clip c for character k (into k's buffers).
  // `advance`: frame t is the previous call's t + 1, whose configuration is already in q_next.
  void reference_at(Character& k, int t, bool advance = false) const noexcept {
    const QuestSimReference& r = (*clips_)[k.clip];
    if (advance) k.q_ref = k.q_next;
    else {
      k.retarget.to_q(k.model, r.pose[t], k.q_ref);
      k.q_ref(1) += k.lift;
    }
    k.retarget.to_q(k.model, r.pose[t + 1], k.q_next);
    k.q_next(1) += k.lift;
    Retarget::velocity(k.model, k.q_ref, k.q_next, S(1.0 / cfg_.control_rate), k.v_ref);
    dynamics::forward_kinematics(k.model, k.ref, k.q_ref, &k.v_ref);
  }

  void restart(int i) noexcept {
    Character& k = *chars_[i];
    std::uniform_real_distribution<double> u(0.0, cum_.back());
    const double x = u(k.rng);
    k.clip = static_cast<int>(std::upper_bound(cum_.begin(), cum_.end(), x) - cum_.begin());
    k.clip = std::min(k.clip, static_cast<int>(cum_.size()) - 1);
    const double before = k.clip ? cum_[k.clip - 1] : 0.0;
    k.t = std::clamp(static_cast<int>(x - before), 0, (*clips_)[k.clip].frames() - NF - 3);
    k.steps = 0;
    k.lift = 0;
    reference_at(k, k.t);
    // The retargeted reference can put a foot into the floor (the avatar's feet are not the
    // performer's: up to 2 cm measured), and a start there launches the character off its springs.
    // Lift the episode's reference so that its first frame's lowest contact point touches y = 0.
    S lowest = std::numeric_limits<S>::infinity();
    for (int p = 0; p < k.model.num_points; ++p) {
      const auto& cp = k.model.points[p];
      lowest = std::min(lowest, (k.ref.p[cp.body] + k.ref.R[cp.body] * cp.pos).y() - cp.radius);
    }
    if (lowest < 0) {
      k.lift = -lowest;
      reference_at(k, k.t);
    }
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    if (cfg_.neutral_start > 0 && u01(k.rng) < cfg_.neutral_start) {
      k.q_after = k.q_neutral;
      control::questsim_stand_under_headset(control::cast_sensor_frame<S>((*clips_)[k.clip].sensor[k.t]), k.q_after);
      k.sim.set_state(k.q_after, k.zero_v);
    } else {
      k.sim.set_state(k.q_ref, k.v_ref);
    }
    k.tau.setZero();
    k.sim.torques() = k.tau;
    k.fy_prev = vertical_forces(k);
  }

  std::array<double, 2> vertical_forces(const Character& k) const noexcept {
    const auto f = k.builder.foot_forces(k.sim);
    return {double(f[0].y()), double(f[1].y())};
  }

  void write_expert(int i) noexcept {
    if (!cfg_.expert) return;  // only DAgger reads them: no inverse dynamics on the PPO path
    Character& k = *chars_[i];
    const S wn = S(cfg_.expert_wn);
    // q_target (-) q in the velocity layout; the target is frame t+1 (a one-frame lead: what the
    // expert did first, measured better without the feedforward) or frame t.
    Retarget::velocity(k.model, k.sim.q(), cfg_.expert_lead ? k.q_next : k.q_ref, S(1), k.err);
    if (cfg_.expert_pd_kp != 0) {  // no model: tau = tau_max (kp (q_target (-) q) + kd (v_ref - v))
      k.tau_exp = k.tau_max.cwiseProduct(S(cfg_.expert_pd_kp) * k.err + S(cfg_.expert_pd_kd) * (k.v_ref - k.sim.v()));
      k.root_need = k.root_left = 0;
      write_expert_actions(i, k);
      return;
    }
    k.qdd = wn * wn * k.err + S(2) * wn * (k.v_ref - k.sim.v());
    if (cfg_.expert_feedforward) {  // + a_ref = (v_ref,t+1 - v_ref,t) / dt (frames t+1, t+2 of the clip)
      const S dt = S(1.0 / cfg_.control_rate);
      k.retarget.to_q(k.model, (*clips_)[k.clip].pose[k.t + 2], k.q_after);
      k.q_after(1) += k.lift;
      Retarget::velocity(k.model, k.q_next, k.q_after, dt, k.v_after);
      k.qdd += (k.v_after - k.v_ref) / dt;
    }
    k.scratch.has_ext = false;
    dynamics::rnea(k.model, k.scratch, k.sim.q(), k.sim.v(), k.qdd, k.tau_exp);
    k.root_need = k.root_left = S(k.tau_exp.template head<6>().norm());
    // The support needs world poses, which RNEA's kinematics leave out: only then a second pass.
    if (cfg_.expert_support) dynamics::forward_kinematics(k.model, k.scratch, k.sim.q(), nullptr);
    if (cfg_.expert_support && stance_support(k)) {
      dynamics::rnea(k.model, k.scratch, k.sim.q(), k.sim.v(), k.qdd, k.tau_exp);
      k.scratch.clear_external();
      k.root_left = S(k.tau_exp.template head<6>().norm());
    }
    write_expert_actions(i, k);
  }

  void write_expert_actions(int i, const Character& k) noexcept {
    float* a = expert_.data() + std::size_t(i) * kActionSize;
    for (int j = 0; j < NJ; ++j) {
      const float x = float(k.tau_exp(6 + j) / k.tau_max(6 + j));
      a[j] = std::isfinite(x) ? std::fmin(1.f, std::fmax(-1.f, x)) : 0.f;
    }
  }

  // Stance support for the expert: the wrench the floating root needs for qdd* (RNEA's root rows,
  // W = (n, f) in root coordinates) is asked from the feet near the ground instead (a contact point
  // within support_height of y = 0), shared between two such feet by the lever rule on the centre
  // of mass's ground projection, each share limited to what a foot contact can give (f_y >= 0,
  // |f_xz| <= mu f_y, centre of pressure within cop_radius of the foot's near points, yaw moment
  // <= yaw_radius f_y); RNEA again with those as external forces gives leg torques that carry the
  // body. What the limits cut is left undone (the root lags and qdd*'s feedback asks again next
  // step). Needs forward kinematics of the state in k.scratch. False when no foot is near the ground.
  bool stance_support(Character& k) const noexcept {
    using V3 = dynamics::Vec3<S>;
    auto& d = k.scratch;
    const auto& m = k.model;
    std::array<V3, 2> centroid{V3::Zero(), V3::Zero()};
    std::array<int, 2> body{-1, -1}, count{0, 0};
    std::array<S, 2> low{S(1), S(1)};
    for (int p = 0; p < m.num_points; ++p) {
      const auto& cp = m.points[p];
      const int side = k.builder.foot_of_body(cp.body);
      if (side < 0) continue;
      const V3 x = d.p[cp.body] + d.R[cp.body] * cp.pos;
      const S y = x.y() - cp.radius;
      if (!(y < S(cfg_.expert_support_height))) continue;
      centroid[side] += V3(x.x(), S(0), x.z());
      ++count[side];
      if (y < low[side]) { low[side] = y; body[side] = cp.body; }
    }
    if (count[0] + count[1] == 0) return false;
    const auto& R0 = d.R[0];
    const V3 p0 = d.p[0];
    const V3 n_w = R0 * V3(k.tau_exp.template head<3>()), f_w = R0 * V3(k.tau_exp.template segment<3>(3));
    if (!(f_w.y() > 0) || !n_w.allFinite() || !f_w.allFinite()) return false;
    std::array<S, 2> alpha{S(count[0] > 0), S(count[1] > 0)};
    for (int s = 0; s < 2; ++s)
      if (count[s]) centroid[s] /= S(count[s]);
    // Two supports: shares by the lever rule at the zero-moment point z (the ground point about
    // which W has no horizontal moment), projected on the segment between the feet.
    V3 z = centroid[0] * alpha[0] + centroid[1] * alpha[1];
    if (count[0] && count[1]) {
      const S ry = -p0.y();
      z = V3(p0.x() + (n_w.z() + ry * f_w.x()) / f_w.y(), S(0), p0.z() + (ry * f_w.z() - n_w.x()) / f_w.y());
      const V3 ab = centroid[1] - centroid[0];
      const S len2 = ab.squaredNorm();
      const S t = len2 > S(1e-6) ? std::clamp((z - centroid[0]).dot(ab) / len2, S(0), S(1)) : S(0.5);
      alpha = {S(1) - t, t};
      z = centroid[0] + t * ab;
    }
    // What the shared forces at z leave of the moment: delta = n_w - (z - p0) x f_w, about z,
    // split by the same shares (sum over feet of m_c + (c - p0) x F = n_w exactly before limits).
    const V3 delta = n_w - (z - p0).cross(f_w);
    for (auto& x : d.fext) x.setZero();
    for (auto& x : d.Kext) x.setZero();
    d.has_ext = true;
    const S mu = S(cfg_.expert_friction), rc = S(cfg_.expert_cop_radius), ry = S(cfg_.expert_yaw_radius);
    for (int s = 0; s < 2; ++s) {
      if (body[s] < 0 || !(alpha[s] > 0)) continue;
      const V3 c = centroid[s];
      V3 F = alpha[s] * f_w;
      // The share's moment about its sole point c (the forces alpha f_w at the centroids already
      // give (z - p0) x f_w).
      V3 mc = alpha[s] * delta;
      const S fh = std::hypot(F.x(), F.z()), fmax = mu * F.y();
      if (fh > fmax) { F.x() *= fmax / fh; F.z() *= fmax / fh; }
      const S mh = std::hypot(mc.x(), mc.z()), mmax = rc * F.y();
      if (mh > mmax) { mc.x() *= mmax / mh; mc.z() *= mmax / mh; }
      mc.y() = std::clamp(mc.y(), -ry * F.y(), ry * F.y());
      // As a wrench at the body's origin, in body coordinates.
      const int b = body[s];
      const V3 mb = mc + (c - d.p[b]).cross(F);
      d.fext[b].template head<3>() = d.R[b].transpose() * mb;
      d.fext[b].template tail<3>() = d.R[b].transpose() * F;
    }
    return true;
  }

  void write_observation(int i, float* out) noexcept {
    Character& k = *chars_[i];
    const QuestSimReference& r = (*clips_)[k.clip];
    for (int j = 0; j <= NF; ++j) k.window[j] = control::cast_sensor_frame<S>(r.sensor[k.t + j]);
    k.builder.build(k.sim, k.window, k.height, out);
    for (int j = 0; j < kObservationSize; ++j)
      if (!std::isfinite(out[j])) out[j] = 0.f;
    if (!cfg_.record_reference) return;
    float* fr = frames_.data() + std::size_t(i) * kFrameSize;
    write_frame(k.sim.data().R[0], k.sim.data().p[0], fr);
    write_frame(k.ref.R[0], k.ref.p[0], fr + 4);
    float* ro = ref_obs_.data() + std::size_t(i) * kObservationSize;
    const std::array<dynamics::Vec3<S>, 2> no_force{dynamics::Vec3<S>::Zero(), dynamics::Vec3<S>::Zero()};
    control::build_quest_sim_observation<NB, NJ, NF>(k.model, k.ref, k.q_ref, k.v_ref, no_force, k.window, k.height, ro);
    for (int j = 0; j < kObservationSize; ++j)
      if (!std::isfinite(ro[j])) ro[j] = 0.f;
  }

  static void write_frame(const dynamics::Mat3<S>& R0, const dynamics::Vec3<S>& p0, float* out) noexcept {
    const auto f = control::QuestSimFloorFrame<S>::from_root(R0, p0);
    out[0] = float(f.c); out[1] = float(f.s); out[2] = float(f.origin.x()); out[3] = float(f.origin.z());
  }

  void step_range(const float* actions, int begin, int end) noexcept {
    for (int i = begin; i < end; ++i) step_one(i, actions + std::size_t(i) * kActionSize);
  }

  void step_one(int i, const float* a) noexcept {
    Character& k = *chars_[i];
    for (int j = 0; j < NJ; ++j) {
      const float x = std::isfinite(a[j]) ? std::fmin(1.f, std::fmax(-1.f, a[j])) : 0.f;
      k.tau(6 + j) = k.tau_max(6 + j) * x;
    }
    k.sim.torques() = k.tau;
    const bool residual = cfg_.residual_max_force > 0 || cfg_.residual_max_torque > 0;
    k.sim.options.root_servo.enabled = residual;
    if (residual) {
      auto& o = k.sim.options.root_servo;
      o.kp_linear = S(cfg_.residual_kp); o.kd_linear = S(cfg_.residual_kd);
      o.kp_angular = S(cfg_.residual_kp_rot); o.kd_angular = S(cfg_.residual_kd_rot);
      o.max_force = S(cfg_.residual_max_force); o.max_torque = S(cfg_.residual_max_torque);
      k.sim.targets().template head<7>() = k.q_next.template head<7>();
      k.sim.target_velocities().template head<6>() = k.v_ref.template head<6>();
    }
    bool failed = false;
    for (int s = 0; s < cfg_.substeps && !failed; ++s) failed = k.sim.step(h_) != dynamics::StepStatus::Ok;
    ++k.t;
    ++k.steps;
    reference_at(k, k.t, true);
    const std::array<double, 2> fy = vertical_forces(k);
    const QuestSimRewardTerms rt = questsim_reward(k.model, k.sim.data(), k.sim.q(), k.sim.v(), k.ref, k.q_ref, k.v_ref,
                                                   k.fy_prev, fy, cfg_.reward);
    k.fy_prev = fy;
    const auto& d = k.sim.data();
    const int head = k.head;
    const bool fell = double(d.p[0].y()) < cfg_.fall_height_ratio * double(k.standing_root_y) ||
                      double(d.R[0](1, 1)) < std::cos(cfg_.fall_tilt);
    const bool lost = double((d.p[head] - k.ref.p[head]).norm()) > cfg_.max_head_error;
    const bool term = failed || fell || lost || !std::isfinite(rt.total);
    const bool trunc = !term && (k.t + NF + 2 >= (*clips_)[k.clip].frames() || k.steps >= cfg_.max_episode_steps);
    reward_[i] = term && failed ? 0.f : float(rt.total);
    for (int j = 0; j < 5; ++j) terms_[std::size_t(i) * 5 + j] = float(rt.r[j]);
    terminated_[i] = failed ? 1 : fell ? 2 : lost ? 3 : term ? 4 : 0;
    truncated_[i] = trunc;
    float* o = obs_.data() + std::size_t(i) * kObservationSize;
    if (term || trunc) {
      if (!failed) {
        write_observation(i, final_obs_.data() + std::size_t(i) * kObservationSize);
        if (cfg_.record_reference) std::copy_n(frames_.data() + std::size_t(i) * kFrameSize, 4, final_frames_.data() + std::size_t(i) * kFrameSize);
      }
      restart(i);
    }
    write_observation(i, o);
    write_expert(i);
  }

  QuestSimEnvConfig cfg_;
  std::shared_ptr<const std::vector<QuestSimReference>> clips_;
  std::vector<double> cum_;  // cumulative usable start frames per clip
  S h_ = S(1.0 / 72);
  std::vector<std::unique_ptr<Character>> chars_;
  std::vector<float> obs_, final_obs_, reward_, terms_, expert_;
  std::vector<float> ref_obs_, frames_, final_frames_;  // config().record_reference
  std::vector<unsigned char> terminated_, truncated_;
};

}  // namespace sparsebody::training
