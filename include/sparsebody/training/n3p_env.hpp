// Batched training environment for a Neural3Points correction policy (issue 14, item 4): N
// characters of the physics mode (avatar/n3p_physics.hpp) per call, each tracking its own reference
// clip with the run-time model-based controller, plus a learned correction of its PD targets.
//
// What the policy does (the fallback to the paper's full policy, stated as such): it does
// not replace the model-based controller (control/model_based_controller.hpp) but corrects the PD
// targets it sets, once per 30 Hz frame,
//   u = q_ref(F + lead) (+) delta,   delta = action_scale * clamp(a, -1, 1)   (rad, per joint DoF)
// (spherical joints: Q_ref exp(delta_j), hinges: theta_ref + delta_j; dynamics::integrate), while the
// feed-forward, the stance support, the velocity targets, the hand correction (§6.2) and the
// bounded residual wrench on the root stay as in the pipeline. a = 0 is exactly the model-based
// controller. The residual bound is the curriculum: train with it annealed to zero (set_residual),
// measure with it off.
//
// Per character and 30 Hz frame F (the frame the character reaches in this step; the pipeline's
// order, avatar/n3p_physics.hpp simulate_frame()):
//   o   = s = {x, g_F+1, g_F+2, g_F+3} (control/n3p_policy_input.hpp, 1008 values): x the simulated
//         character before the step, g the reference frames after F, all in the heading of the
//         reference at F (its root's forward on the floor). At run time the pipeline has exactly
//         these: its output is kDelayFrames = 3 frames behind its newest reference.
//   a   -> targets u (above); controller.set_reference(q(F-2), q(F-1), q(F)); 4 substeps of 1/120 s
//   r   = the QuestSim imitation reward against the reference at F (training/questsim_reward.hpp,
//         same kernels) + residual_weight exp(-|F_res| / (m g)) (mean applied residual force over
//         the substeps): while a residual helps, using less of it pays.
//   termination: the pipeline's fall rule (control/n3p_recovery.hpp: height, tilt, diverging root)
//     or a failed substep; truncation: the clip ends or max_episode_steps.
// Reference: the clip's pose (QuestSimReference at 30 Hz) retargeted to the avatar
// (control/n3p_sim_retarget.hpp). At run time it is the direct-mode prediction instead: a
// policy trained here sees clean references and meets predicted ones there.
// Support weights of the stance support: 1 for a foot whose reference sole is within
// contact_height of the floor (the pipeline passes the predicted contact probabilities), gated by
// the simulated contacts as in the pipeline (support_on_contact).
// Restarts (reference-state initialisation): a clip drawn with probability ~ its length, a frame
// uniform in it, the character on the reference lifted out of the floor (the pipeline's placement)
// with the reference velocity, or at rest with probability rest_start (how the pipeline starts).
// Determinism: each character has its own random stream seeded from (seed, index). The constructor
// allocates everything; step() with threads = 1 allocates nothing.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <random>
#include <stdexcept>
#include <thread>
#include <utility>
#include <vector>

#include "sparsebody/character/avatar.hpp"
#include "sparsebody/control/fall_detector.hpp"
#include "sparsebody/control/model_based_controller.hpp"
#include "sparsebody/control/n3p_recovery.hpp"
#include "sparsebody/control/n3p_sim_retarget.hpp"
#include "sparsebody/control/n3p_target_correction.hpp"
#include "sparsebody/control/tracker_correction.hpp"
#include "sparsebody/dynamics/simulator.hpp"
#include "sparsebody/predict/n3p_meta.hpp"
#include "sparsebody/training/questsim_reference.hpp"
#include "sparsebody/training/questsim_reward.hpp"

namespace sparsebody::training {

struct N3PEnvConfig {
  character::AvatarOptions avatar{};                  // the pipeline's: 1.75 m, 63 kg, kp 200, kd 20
  control::ModelBasedControllerConfig controller{};  // its residual bound is set_residual's
  control::TrackerCorrectionConfig correction{};
  control::FallDetectorConfig fall{};
  int substeps = 4;         // per 30 Hz frame (120 Hz)
  int contact_passes = 3;   // N3PPhysicsConfig::contact_passes
  double action_scale = 0.2;       // rad of target correction per unit action
  int max_episode_steps = 300;     // frames (10 s)
  double rest_start = 0.2;         // share of restarts at rest (the pipeline's start)
  double contact_height = 0.03;    // m: a reference sole this low is a support
  double residual_weight = 0.2;    // reward for leaving the residual unused (see above)
  QuestSimRewardConfig reward{};
};

class N3PEnv {
 public:
  using S = float;
  static constexpr int MB = 24, MD = 72;
  using Model = dynamics::Model<S, MB, MD>;
  using Sim = dynamics::Simulator<S, MB, MD>;
  using Data = dynamics::Data<S, MB, MD>;
  using VecQ = typename Model::VecQ;
  using VecV = typename Model::VecV;
  using Retarget = control::N3PSimRetarget<S, MB, MD>;
  static constexpr int kObservationSize = control::n3p_policy::kPolicyIn;  // 1008
  static constexpr int kActionSize = character::kDefaultAvatarJointDofs;   // 48
  static constexpr int kRing = 8;                                          // reference frames F-2 .. F+4 (7) kept

  // clips: reference motions at 30 Hz (make_questsim_reference(..., 30.0)) in the standard skeleton of meta.
  N3PEnv(std::shared_ptr<const std::vector<QuestSimReference>> clips, const predict::N3PMeta& meta, int characters,
         unsigned long long seed, N3PEnvConfig cfg = {})
      : cfg_(cfg), clips_(std::move(clips)), meta_(meta) {
    if (!clips_ || clips_->empty()) throw std::invalid_argument("N3PEnv: no reference clips");
    if (characters < 1) throw std::invalid_argument("N3PEnv: no characters");
    for (const auto& c : *clips_) {
      if (std::fabs(c.rate - 30.0) > 1e-9) throw std::invalid_argument("N3PEnv: reference clips must be at 30 Hz (" + c.source + ")");
      cum_.push_back((cum_.empty() ? 0.0 : cum_.back()) + std::max(0, c.frames() - kMinFrames));
    }
    if (!(cum_.back() > 0)) throw std::invalid_argument("N3PEnv: every clip is shorter than the policy's window");
    for (int i = 0; i < characters; ++i) chars_.push_back(std::make_unique<Character>(meta_, cfg_, seed, i));
    obs_.assign(std::size_t(characters) * kObservationSize, 0.f);
    final_obs_ = obs_;
    reward_.assign(std::size_t(characters), 0.f);
    terms_.assign(std::size_t(characters) * 6, 0.f);
    terminated_.assign(std::size_t(characters), 0);
    truncated_.assign(std::size_t(characters), 0);
    set_residual(cfg_.controller.max_force, cfg_.controller.max_torque);
    reset_all();
  }

  int size() const noexcept { return static_cast<int>(chars_.size()); }

  void reset_all() noexcept {
    for (int i = 0; i < size(); ++i) {
      restart(*chars_[i]);
      write_observation(*chars_[i], obs_.data() + std::size_t(i) * kObservationSize);
    }
  }

  // actions: size() x kActionSize, row-major (non-finite -> 0, clamped to [-1, 1]).
  void step(const float* actions, int threads = 1) {
    const int n = size();
    threads = std::max(1, std::min({threads, n, 64}));
    if (threads == 1) {
      for (int i = 0; i < n; ++i) step_one(i, actions + std::size_t(i) * kActionSize);
      return;
    }
    std::array<std::thread, 64> pool;
    auto run = [this, actions, n, threads](int k) {
      for (int i = n * k / threads; i < n * (k + 1) / threads; ++i) step_one(i, actions + std::size_t(i) * kActionSize);
    };
    for (int k = 1; k < threads; ++k) pool[k] = std::thread(run, k);
    run(0);
    for (int k = 1; k < threads; ++k) pool[k].join();
  }

  // The residual wrench's bound on every character (N, N m): the curriculum. 0 0 = none.
  void set_residual(double max_force, double max_torque) noexcept {
    for (auto& c : chars_) {
      c->controller.config().max_force = max_force;
      c->controller.config().max_torque = max_torque;
    }
    residual_ = {max_force, max_torque};
  }
  std::array<double, 2> residual() const noexcept { return residual_; }
  const N3PEnvConfig& config() const noexcept { return cfg_; }

  float* observations() noexcept { return obs_.data(); }
  const float* final_observations() const noexcept { return final_obs_.data(); }
  const float* rewards() const noexcept { return reward_.data(); }
  // n x 6: r(q), r(qd), r(x), r(xd), r_f, and the mean applied residual force of the step (N).
  const float* reward_terms() const noexcept { return terms_.data(); }
  // Why each character's episode ended this step: 0 it did not, 1 a failed substep, 2 a fall
  // (control::FallReason Height / Tilt / Diverged: 2 / 3 / 4).
  const unsigned char* terminated() const noexcept { return terminated_.data(); }
  const unsigned char* truncated() const noexcept { return truncated_.data(); }
  int clip(int i) const noexcept { return chars_[i]->clip; }
  int frame(int i) const noexcept { return chars_[i]->f; }  // the last frame reached
  int episode_step(int i) const noexcept { return chars_[i]->steps; }
  double residual_force(int i) const noexcept { return chars_[i]->residual_mean; }
  const Sim& simulator(int i) const noexcept { return chars_[i]->sim; }
  const Model& model() const noexcept { return chars_[0]->model; }
  // q_ref of frame frame(i) + k (k clamped to -2 .. 4), retargeted and lifted as this episode's.
  const VecQ& reference_q(int i, int k = 0) const noexcept { return chars_[i]->q(chars_[i]->f + std::clamp(k, -2, 4)); }
  const VecQ& targets(int i) const noexcept { return chars_[i]->sim.targets(); }

 private:
  static constexpr int kLead = 2;  // ModelBasedControllerConfig::target_lead's default; checked below
  static constexpr int kMinFrames = 8;  // F-2 .. F+4 around a frame, plus one

  struct Character {
    Model model;
    Sim sim;
    Retarget retarget;
    control::ModelBasedController<S, MB, MD> controller;
    control::TrackerCorrection<S, MB, MD> correction;
    control::N3PRecovery<S, MB, MD> recovery;
    std::array<VecQ, kRing> ring_q;
    std::array<VecV, kRing> ring_v;
    std::array<Data, kRing> ring_d;
    std::array<int, kRing> ring_frame;
    VecQ q_place;
    VecV tau, delta;
    std::array<int, 4> foot_bodies{};  // Foot_L, Toes_L, Foot_R, Toes_R
    std::array<double, 2> fy_prev{};
    std::mt19937_64 rng;
    S lift = 0;
    int clip = 0, f = 0, steps = 0;
    double residual_mean = 0;
    double weight = 0;  // m g (N)

    Character(const predict::N3PMeta& meta, const N3PEnvConfig& cfg, unsigned long long seed, int index)
        : model(character::default_avatar<S, MB, MD>(cfg.avatar)),
          sim(model),
          retarget(Retarget::from_meta(model, meta)),
          controller(model, cfg.controller),
          correction(model, cfg.correction),
          recovery(model, retarget.body_of(0), cfg.fall, cfg.controller.ground_resets),
          ring_d{make_data<kRing>(model)},
          rng(seed * 0x9E3779B97F4A7C15ull + std::uint64_t(index) + 1) {
      if (cfg.controller.target_lead != kLead) throw std::invalid_argument("N3PEnv: target_lead must be 2 (the observation's window)");
      sim.options.contact.max_passes = cfg.contact_passes;
      ring_q.fill(model.neutral_configuration());
      ring_v.fill(VecV::Zero(model.nv));
      ring_frame.fill(-1);
      q_place = model.neutral_configuration();
      tau = delta = VecV::Zero(model.nv);
      const char* feet[4] = {"Foot_L", "Toes_L", "Foot_R", "Toes_R"};
      for (int k = 0; k < 4; ++k) {
        foot_bodies[k] = model.find(feet[k]);
        if (foot_bodies[k] < 0) throw std::invalid_argument(std::string("N3PEnv: the avatar has no body ") + feet[k]);
      }
      double mass = 0;
      for (int b = 0; b < model.nb; ++b) mass += double(model.bodies[b].mass);
      weight = 9.81 * mass;
    }
    template <int N>
    static std::array<Data, N> make_data(const Model& m) {
      return make_data_impl(m, std::make_index_sequence<N>{});
    }
    template <std::size_t... I>
    static std::array<Data, sizeof...(I)> make_data_impl(const Model& m, std::index_sequence<I...>) {
      return {{((void)I, Data(m))...}};
    }
    const VecQ& q(int frame) const noexcept { return ring_q[frame % kRing]; }
    const VecV& v(int frame) const noexcept { return ring_v[frame % kRing]; }
    const Data& d(int frame) const noexcept { return ring_d[frame % kRing]; }
  };

  // Frame k of the character's clip into its ring (configuration, velocity from k - 1, world
  // kinematics with that velocity). Frames are added in increasing order after a restart.
  void load_frame(Character& c, int k) const noexcept {
    const int slot = k % kRing;
    if (c.ring_frame[slot] == k) return;
    const QuestSimReference& r = (*clips_)[c.clip];
    c.retarget.to_q(c.model, r.pose[k], c.ring_q[slot]);
    c.ring_q[slot](c.model.bodies[c.retarget.body_of(0)].q_index + 1) += c.lift;
    if (k > 0 && c.ring_frame[(k - 1) % kRing] == k - 1)
      Retarget::velocity(c.model, c.ring_q[(k - 1) % kRing], c.ring_q[slot], S(1.0 / 30), c.ring_v[slot]);
    else
      c.ring_v[slot].setZero();
    dynamics::forward_kinematics(c.model, c.ring_d[slot], c.ring_q[slot], &c.ring_v[slot], true);
    c.ring_frame[slot] = k;
  }

  void restart(Character& c) noexcept {
    std::uniform_real_distribution<double> u(0.0, cum_.back());
    const double x = u(c.rng);
    c.clip = std::min(static_cast<int>(std::upper_bound(cum_.begin(), cum_.end(), x) - cum_.begin()),
                      static_cast<int>(cum_.size()) - 1);
    const double before = c.clip ? cum_[c.clip - 1] : 0.0;
    const int frames = (*clips_)[c.clip].frames();
    // the character stands at frame f = s; frames s-2 .. s+5 must exist (the first step reaches s+1)
    c.f = std::clamp(static_cast<int>(x - before) + 2, 2, frames - 6);
    c.steps = 0;
    c.lift = 0;
    c.ring_frame.fill(-1);
    for (int k = c.f - 2; k <= c.f + 4; ++k) load_frame(c, k);
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    const bool rest = u01(c.rng) < cfg_.rest_start;
    c.recovery.start(c.model, c.sim, c.controller, c.q(c.f));  // the pipeline's placement (lifted, at rest)
    if (!rest) {
      c.q_place = c.sim.q();
      c.sim.set_state(c.q_place, c.v(c.f));
    }
    c.sim.targets() = c.q(c.f);
    c.sim.target_velocities().setZero();
    c.controller.reset();
    c.tau.setZero();
    c.sim.torques() = c.tau;
    c.fy_prev = vertical_foot_forces(c);
    c.residual_mean = 0;
  }

  std::array<double, 2> vertical_foot_forces(const Character& c) const noexcept {
    std::array<double, 2> fy{};
    for (int k = 0; k < c.sim.num_contacts(); ++k) {
      const auto& ct = c.sim.contact_at(k);
      if (!ct.active) continue;
      for (int b = 0; b < 4; ++b)
        if (ct.body == c.foot_bodies[b]) fy[b / 2] += double(ct.force.y());
    }
    return fy;
  }

  bool sim_foot_contact(const Character& c, int side) const noexcept {
    for (int k = 0; k < c.sim.num_contacts(); ++k) {
      const auto& ct = c.sim.contact_at(k);
      if (ct.active && (ct.body == c.foot_bodies[2 * side] || ct.body == c.foot_bodies[2 * side + 1])) return true;
    }
    return false;
  }

  // Whether the reference's foot (side) has a contact point within contact_height of the floor at frame k.
  bool reference_support(const Character& c, int k, int side) const noexcept {
    const Data& d = c.d(k);
    for (int p = 0; p < c.model.num_points; ++p) {
      const auto& cp = c.model.points[p];
      if (cp.body != c.foot_bodies[2 * side] && cp.body != c.foot_bodies[2 * side + 1]) continue;
      if ((d.p[cp.body] + d.R[cp.body] * cp.pos).y() - cp.radius < S(cfg_.contact_height)) return true;
    }
    return false;
  }

  // s = {x, g_F+1..F+3} (control/n3p_target_correction.hpp), F = c.f + 1 (the frame the next step reaches).
  void write_observation(Character& c, float* out) const noexcept {
    const int F = c.f + 1;
    control::n3p_correction::write_input<float>(c.retarget, c.sim.data(), {&c.d(F), &c.d(F + 1), &c.d(F + 2), &c.d(F + 3)}, out);
  }

  void step_one(int i, const float* a) noexcept {
    Character& c = *chars_[i];
    const int F = c.f + 1;  // the frame this step reaches
    load_frame(c, F + 4);   // the next observation's last reference frame
    const S dt = S(1.0 / 30), h = dt / S(cfg_.substeps);
    double support[2];
    for (int s = 0; s < 2; ++s) {
      support[s] = reference_support(c, F, s) ? 1.0 : 0.0;
      if (cfg_.controller.support_on_contact && !sim_foot_contact(c, s)) support[s] = 0.0;
    }
    c.controller.set_reference(c.model, c.q(F - 2), c.q(F - 1), c.q(F), dt, support);
    // u = q_ref(F + lead) (+) delta
    VecQ& u = c.sim.targets();
    u = c.q(F + kLead);
    control::n3p_correction::apply(c.model, a, cfg_.action_scale, c.delta, u);
    if (cfg_.controller.velocity_targets) c.sim.target_velocities() = c.controller.reference_velocity();
    const Data& dF = c.d(F);
    const dynamics::Vec3<S> hands[2] = {dF.p[c.correction.hand_body(0)], dF.p[c.correction.hand_body(1)]};
    const bool present[2] = {true, true};
    bool failed = false;
    double residual = 0;
    for (int k = 0; k < cfg_.substeps; ++k) {
      c.controller.apply(c.model, c.sim, S(k + 1) / S(cfg_.substeps), c.tau);
      c.correction.apply(c.model, c.sim.data(), hands, present, c.tau);
      c.sim.torques() = c.tau;
      if (c.sim.step(h) != dynamics::StepStatus::Ok) {
        failed = true;
        break;
      }
      residual += c.controller.residual_applied(c.sim).force;
    }
    c.residual_mean = residual / cfg_.substeps;
    c.f = F;
    ++c.steps;
    const std::array<double, 2> fy = vertical_foot_forces(c);
    QuestSimRewardTerms rt{};
    control::FallReason why = control::FallReason::None;
    if (!failed) {
      rt = questsim_reward(c.model, c.sim.data(), c.sim.q(), c.sim.v(), dF, c.q(F), c.v(F), c.fy_prev, fy, cfg_.reward);
      why = c.recovery.check(c.model, c.sim, c.controller, c.q(F - 1), c.q(F));
    }
    c.fy_prev = fy;
    const float r = float(rt.total + cfg_.residual_weight * std::exp(-c.residual_mean / c.weight));
    const bool term = failed || why != control::FallReason::None || !std::isfinite(r);
    const bool trunc = !term && (F + 6 >= (*clips_)[c.clip].frames() || c.steps >= cfg_.max_episode_steps);
    reward_[i] = term ? 0.f : r;
    for (int j = 0; j < 5; ++j) terms_[std::size_t(i) * 6 + j] = float(rt.r[j]);
    terms_[std::size_t(i) * 6 + 5] = float(c.residual_mean);
    terminated_[i] = failed ? 1 : why != control::FallReason::None ? static_cast<unsigned char>(1 + static_cast<int>(why)) : term ? 1 : 0;
    truncated_[i] = trunc;
    float* o = obs_.data() + std::size_t(i) * kObservationSize;
    if (term || trunc) {
      if (trunc) write_observation(c, final_obs_.data() + std::size_t(i) * kObservationSize);
      restart(c);
    }
    write_observation(c, o);
  }

  N3PEnvConfig cfg_;
  std::shared_ptr<const std::vector<QuestSimReference>> clips_;
  predict::N3PMeta meta_;
  std::vector<double> cum_;
  std::vector<std::unique_ptr<Character>> chars_;
  std::vector<float> obs_, final_obs_, reward_, terms_;
  std::vector<unsigned char> terminated_, truncated_;
  std::array<double, 2> residual_{};
};

}  // namespace sparsebody::training
