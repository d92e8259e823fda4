// Batched training environment for the QuestSim torque policy (Winkler et al. 2022, §3, App. A):
// N simulated characters stepped per call, each tracking its own reference clip. The run-time
// pipeline's pieces, unchanged: the same avatar model (character::avatar_for_user_height, joint
// damping 0.1), the same Simulator in torque mode at 2 substeps of 1/72 s, the same observation
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
// reference would do, for every character's current state: computed-torque control towards the
// reference frame t+1, qdd* = wn^2 (q_ref,t+1 (-) q) + 2 wn (v_ref - v) (critically damped,
// wn = expert_wn), tau = RNEA(q, v, qdd*) on the non-root DoFs, a = clamp(tau / tau_max). RNEA of
// the floating body carries no body weight through the legs (the root's share is left to contacts
// or the residual force), so the expert tracks only with a residual, and not well: measured on 40
// training clips with a 1000 N / 300 N m residual, mean reward 0.47 against 0.31 for zero torques
// (positions r(x) 0.70 against 0.22), but the knees flex past the reference (1 rad after 12
// steps) because the legs' load is not in the model. A starting point, not yet a teacher.
// Determinism: every character has its own random stream seeded from (seed, index), so results do
// not depend on the thread count. The constructor allocates everything; step() with threads = 1
// allocates nothing (threads > 1 starts std::threads for the call, which does).
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <random>
#include <stdexcept>
#include <thread>
#include <vector>

#include "sparsebody/character/avatar.hpp"
#include "sparsebody/control/n3p_sim_retarget.hpp"
#include "sparsebody/control/questsim_actuation.hpp"
#include "sparsebody/control/questsim_observation.hpp"
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
  double fall_height_ratio = 0.5, fall_tilt = 1.2;  // the pipeline's fall rule (QuestSimConfig)
  double max_head_error = 0.5;    // m: early termination (tracking lost)
  int max_episode_steps = 300;    // control steps (8.3 s)
  double residual_max_force = 0;  // N: root servo bound (0: off)
  double residual_max_torque = 0; // N m
  double residual_kp = 2000, residual_kd = 200, residual_kp_rot = 400, residual_kd_rot = 40;
  bool expert = false;            // compute expert_actions() (one RNEA per character and step)
  double expert_wn = 15;          // rad/s: natural frequency of the expert's tracking
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
    for (int i = 0; i < n; ++i) {
      restart(i);
      write_observation(i, obs_.data() + std::size_t(i) * kObservationSize);
      write_expert(i);
    }
  }

  int size() const noexcept { return static_cast<int>(chars_.size()); }

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
  const float* expert_actions() const noexcept { return expert_.data(); }  // n x kActionSize, see above (zeros unless config().expert)  // n x 5: r(q), r(qd), r(x), r(xd), r_f
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
    VecQ q_ref, q_next;
    VecV v_ref, tau, zero_v, tau_max, err, qdd, tau_exp;
    typename Builder::UserWindow window{};
    std::mt19937_64 rng;
    S height;
    S standing_root_y = 1;
    std::array<double, 2> fy_prev{};
    int clip = 0, t = 0, steps = 0;
    int head = 0;  // the Head body

    Character(const predict::N3PMeta& meta, double h, const QuestSimEnvConfig& cfg, unsigned long long seed, std::size_t index)
        : model(make_model(h, cfg)), sim(model), builder(model), retarget(Retarget::from_meta(model, meta)), ref(model), scratch(model),
          rng(seed * 0x9E3779B97F4A7C15ull + index + 1), height(S(h)) {
      sim.options.mode = dynamics::ControlMode::Torque;
      q_ref = q_next = model.neutral_configuration();
      v_ref = tau = zero_v = err = qdd = tau_exp = VecV::Zero(model.nv);
      standing_root_y = q_ref(1);
      tau_max = control::questsim_torque_limits(model, h / character::AvatarOptions{}.height,
                                                cfg.per_joint_torque_limits ? 0.0 : cfg.torque_scale);
      head = model.find("Head");
      if (head < 0) throw std::invalid_argument("QuestSimEnv: the avatar has no Head body");
    }
    static Model make_model(double h, const QuestSimEnvConfig& cfg) {
      Model m = character::avatar_for_user_height<S, MB, MD>(h);
      for (int i = 1; i < m.nb; ++i) m.bodies[i].damping = S(cfg.joint_damping);
      m.finalize();
      return m;
    }
  };

  // Reference configuration and velocity at frame t of clip c for character k (into k's buffers).
  // `advance`: frame t is the previous call's t + 1, whose configuration is already in q_next.
  void reference_at(Character& k, int t, bool advance = false) const noexcept {
    const QuestSimReference& r = (*clips_)[k.clip];
    if (advance) k.q_ref = k.q_next;
    else k.retarget.to_q(k.model, r.pose[t], k.q_ref);
    k.retarget.to_q(k.model, r.pose[t + 1], k.q_next);
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
    reference_at(k, k.t);
    k.sim.set_state(k.q_ref, k.v_ref);
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
    Retarget::velocity(k.model, k.sim.q(), k.q_next, S(1), k.err);  // q_ref,t+1 (-) q in the velocity layout
    k.qdd = wn * wn * k.err + S(2) * wn * (k.v_ref - k.sim.v());
    dynamics::rnea(k.model, k.scratch, k.sim.q(), k.sim.v(), k.qdd, k.tau_exp);
    float* a = expert_.data() + std::size_t(i) * kActionSize;
    for (int j = 0; j < NJ; ++j) {
      const float x = float(k.tau_exp(6 + j) / k.tau_max(6 + j));
      a[j] = std::isfinite(x) ? std::fmin(1.f, std::fmax(-1.f, x)) : 0.f;
    }
  }

  void write_observation(int i, float* out) noexcept {
    Character& k = *chars_[i];
    const QuestSimReference& r = (*clips_)[k.clip];
    for (int j = 0; j <= NF; ++j) {
      const auto& s = r.sensor[k.t + j];
      for (int d = 0; d < 3; ++d) {
        k.window[j][d].position = s[d].position.template cast<S>();
        k.window[j][d].rotation = s[d].rotation.template cast<S>();
      }
    }
    k.builder.build(k.sim, k.window, k.height, out);
    for (int j = 0; j < kObservationSize; ++j)
      if (!std::isfinite(out[j])) out[j] = 0.f;
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
      if (!failed) write_observation(i, final_obs_.data() + std::size_t(i) * kObservationSize);
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
  std::vector<unsigned char> terminated_, truncated_;
};

}  // namespace sparsebody::training
