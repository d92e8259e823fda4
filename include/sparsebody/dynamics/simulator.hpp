// The simulation step, staged like MuJoCo's mj_step: check the input, actuation (PD servos or
// direct torques, passive damping, root servo), collision (contact candidates), the solve (ABA with
// implicit damping, contact active set, root servo bounds), the root servo's report, semi-implicit
// Euler, check the result. Everything it touches is a fixed-size member, so step() never
// allocates, and it never throws.
//
// State layout: q (nq) and v (nv) as described in joint.hpp; body poses/velocities of the current
// state are in data() after every step (R[i], p[i]: world orientation/position of body i's joint
// frame; v[i]: body-frame spatial velocity).
//
// Recovery: non-finite input makes step() return at once; a failed solve, a non-finite result or
// any |v_k| above `velocity_limit` restores the pre-step state and returns the failure status;
// nothing is propagated. The caller decides what to do (typically set_state() with a fresh pose and
// zero velocity, as Neural3Points' rollouts reset the character).
#pragma once
#include <algorithm>
#include <ostream>

#include "sparsebody/dynamics/aba.hpp"
#include "sparsebody/dynamics/contact.hpp"
#include "sparsebody/dynamics/integrator.hpp"
#include "sparsebody/dynamics/pd_servo.hpp"
#include "sparsebody/dynamics/root_servo.hpp"

namespace sparsebody::dynamics {

enum class StepStatus : unsigned char {
  Ok = 0,
  NonFiniteInput,    // q, v, torques or targets contained NaN/Inf; nothing was done
  NonFiniteResult,   // the new state was not finite; rolled back
  VelocityLimit,     // |v_k| > velocity_limit after the step; rolled back
  SolverFailure,     // a joint-space inertia term was not positive definite; rolled back
};
inline const char* status_name(StepStatus s) {
  switch (s) {
    case StepStatus::Ok: return "ok";
    case StepStatus::NonFiniteInput: return "non-finite input";
    case StepStatus::NonFiniteResult: return "non-finite result";
    case StepStatus::VelocityLimit: return "velocity limit exceeded";
    default: return "solver failure";
  }
}

inline std::ostream& operator<<(std::ostream& os, StepStatus s) { return os << status_name(s); }

enum class ControlMode : unsigned char {
  PdTargets,  // Neural3Points: tau = PD(q_target) + tau_user, servo damping implicit
  Torque,     // QuestSim: tau = tau_user, only passive joint damping implicit
};

// Settings of the step (may be changed between steps).
template <class S>
struct SimulatorOptions {
  ControlMode mode = ControlMode::PdTargets;
  bool implicit_damping = true;     // false: explicit servo damping (for comparison only)
  S velocity_limit = S(500);        // rad/s or m/s on any coordinate
  bool contacts_enabled = true;
  bool warm_start_contacts = true;  // sliding contacts start from last step's damper (fewer solver passes)
  ContactParams<S> contact;
  RootServoOptions<S> root_servo;   // off by default; needs a free root
};

template <class S, int MB, int MD, int MaxContacts = 64, int MaxBoxes = 8>
class Simulator {
 public:
  using ModelT = Model<S, MB, MD>;
  using VecQ = typename ModelT::VecQ;
  using VecV = typename ModelT::VecV;

  SimulatorOptions<S> options;
  Environment<S, MaxBoxes> env;     // ground plane and static boxes

  explicit Simulator(const ModelT& model, const SimulatorOptions<S>& opt = SimulatorOptions<S>{})
      : options(opt), m_(model), d_(model), root_servo_(model.root_body()) {
    q_ = m_.neutral_configuration();
    v_.setZero(m_.nv);
    q_target_ = q_;
    v_target_.setZero(m_.nv);
    tau_user_.setZero(m_.nv);
    tau_.setZero(m_.nv);
    qdd_.setZero(m_.nv);
    q_prev_ = q_;
    v_prev_ = v_;
    env.ground_normal = -m_.gravity.normalized();
    refresh_kinematics();
  }

  const ModelT& model() const { return m_; }
  const Data<S, MB, MD>& data() const { return d_; }
  const VecQ& q() const { return q_; }
  const VecV& v() const { return v_; }
  const VecV& last_acceleration() const { return qdd_; }
  // A new state (start, reset, teleport): the last step's contacts no longer describe it, so the
  // contact warm start and the failure rollback start from here (a reset is a clean start, and the
  // same state gives the same steps whatever ran before: tests/questsim/test_determinism.cpp).
  void set_state(const VecQ& q, const VecV& v) {
    q_ = q;
    v_ = v;
    q_prev_ = q_;
    v_prev_ = v_;
    nc_ = 0;
    current_ = 0;
    refresh_kinematics();
  }
  // The numbers of a model with the same tree (a rescaled avatar: another user's height; masses,
  // inertias, geometry, gains, limits): the state goes to the new model's reference configuration
  // at rest, as a new simulator would start (call set_state after). No allocation. False
  // (nothing changed) when the tree differs (Model::same_topology).
  bool set_model_parameters(const ModelT& m) noexcept {
    if (!m_.assign_parameters(m)) return false;
    env.ground_normal = -m_.gravity.normalized();
    set_state(m_.neutral_configuration(), VecV::Zero(m_.nv));
    return true;
  }
  // PD targets in the configuration layout (quaternions for spherical joints, angles for revolute).
  // The free root's entries are the root servo's target (velocities in the target's body frame).
  VecQ& targets() { return q_target_; }
  const VecQ& targets() const { return q_target_; }
  VecV& target_velocities() { return v_target_; }
  // Generalised torques added in both modes (free root entries: body-frame wrench).
  VecV& torques() { return tau_user_; }
  // Convenience: target of one spherical joint (joint-frame rotation, child relative to parent).
  void set_target(int body, const Quat<S>& rot) {
    const int k = m_.bodies[body].q_index;
    q_target_(k) = rot.w(); q_target_(k + 1) = rot.x(); q_target_(k + 2) = rot.y(); q_target_(k + 3) = rot.z();
  }
  void set_target(int body, S angle) { q_target_(m_.bodies[body].q_index) = angle; }

  int num_contacts() const { return nc_; }
  int num_active_contacts() const {
    int n = 0;
    for (int k = 0; k < nc_; ++k) n += contacts()[k].active ? 1 : 0;
    return n;
  }
  const Contact<S>& contact_at(int k) const { return contacts()[k]; }
  int contact_overflow() const { return overflow_; }
  int last_passes() const { return passes_; }
  // World-frame wrench the root servo applied in the last step (explicit + implicit part; zero when off).
  const Vec3<S>& root_servo_force() const { return root_servo_.force(); }
  const Vec3<S>& root_servo_torque() const { return root_servo_.torque(); }

  StepStatus step(S h) {
    const bool servo_root = options.root_servo.enabled && root_servo_.available();
    if (!input_finite(servo_root)) return StepStatus::NonFiniteInput;
    q_prev_ = q_;
    v_prev_ = v_;
    const S hd = options.implicit_damping ? h : S(0);  // h of the implicit terms
    actuation(hd, servo_root);
    collision();
    if (!solve(h, hd, servo_root)) return rollback(StepStatus::SolverFailure);
    if (servo_root) root_servo_.report(m_, d_, hd, qdd_);
    integrate(m_, q_, v_, qdd_, h);
    return check_result();
  }

 private:
  void refresh_kinematics() { forward_kinematics(m_, d_, q_, &v_); }

  // Check input: the state, the torques and, when a servo reads them, the targets are finite.
  bool input_finite(bool servo_root) const {
    const bool targets_used = options.mode == ControlMode::PdTargets || servo_root;
    return q_.allFinite() && v_.allFinite() && tau_user_.allFinite() &&
           (!targets_used || (q_target_.allFinite() && v_target_.allFinite()));
  }

  // Actuation: explicit torques (PD servos or passive damping, plus the user's torques and the
  // root servo's explicit wrench) into tau_, and their implicit damping into ABA's diagonal.
  void actuation(S hd, bool servo_root) {
    const bool servos = options.mode == ControlMode::PdTargets;
    if (servos) pd_torques(m_, q_, v_, q_target_, v_target_, tau_);
    else passive_torques(m_, v_, tau_);
    tau_ += tau_user_;
    implicit_damping_diagonal(m_, hd, servos, d_.implicit_diagonal);
    root_servo_.clear_report();
    if (servo_root) {
      root_servo_.add_explicit(options.root_servo, m_, d_, q_target_, v_, v_target_, tau_);
      root_servo_.write_implicit(m_, hd, d_.implicit_diagonal);
    }
  }

  // Collision: contact candidates of the current poses. Two buffers, flipped: the previous step's
  // contacts stay readable for the warm start (see detect_contacts) without copying them.
  void collision() {
    if (!options.contacts_enabled) {
      nc_ = 0;
      return;
    }
    const int prev = current_;
    current_ ^= 1;
    nc_ = detect_contacts(m_, d_, env, options.contact, contacts(), overflow_, contact_buffers_[prev].data(),
                          options.warm_start_contacts ? nc_ : 0);
  }

  // Solve: qdd_ from ABA on the kinematics already in d_ (from the previous step or set_state),
  // with the contact active set and the root servo's bounds. False on a solver failure.
  bool solve(S h, S hd, bool servo_root) {
    velocity_product_forces(m_, d_);  // pass 1's p_i
    passes_ = 0;
    bool ok = nc_ == 0 ? solve_free() : solve_contacts(h);
    if (servo_root) ok = bound_root_servo(hd, ok);
    d_.has_ext = false;
    return ok;
  }
  bool solve_free() {
    d_.has_ext = false;
    passes_ = 1;
    return aba_solve(m_, d_, tau_, qdd_);
  }
  // Contact solve: at most max_passes ABA solves (at least the one a step needs), each after
  // assembling the active contacts, until the active set settles.
  bool solve_contacts(S h) {
    const ContactParams<S>& par = options.contact;
    const int max_passes = std::max(1, par.max_passes);
    bool ok = true;
    for (int pass = 0; pass < max_passes; ++pass) {
      assemble_contacts(m_, d_, contacts(), nc_, par, h);
      ok = aba_solve(m_, d_, tau_, qdd_);
      ++passes_;
      if (!ok || !update_contact_set(m_, d_, contacts(), nc_, par, h)) break;
    }
    return ok;
  }
  // A root servo block whose implicit part took it past its bound is re-solved as that bound
  // alone (same contact assembly: one more ABA solve, only on such steps; at most two, as the
  // re-solve of one block changes the other's implicit part).
  bool bound_root_servo(S hd, bool ok) {
    for (int k = 0; k < 2 && ok && root_servo_.rebound(options.root_servo, m_, hd, qdd_, tau_); ++k) {
      root_servo_.write_implicit(m_, hd, d_.implicit_diagonal);
      ok = aba_solve(m_, d_, tau_, qdd_);
      ++passes_;
    }
    return ok;
  }

  // Check result: finite and within the velocity limit, else rolled back; then the kinematics of
  // the new state (the next step's collision and pass 1 start from them).
  StepStatus check_result() {
    if (!q_.allFinite() || !v_.allFinite()) return rollback(StepStatus::NonFiniteResult);
    if (v_.cwiseAbs().maxCoeff() > options.velocity_limit) return rollback(StepStatus::VelocityLimit);
    refresh_kinematics();
    return StepStatus::Ok;
  }
  StepStatus rollback(StepStatus s) {
    q_ = q_prev_;
    v_ = v_prev_;
    d_.has_ext = false;
    refresh_kinematics();
    return s;
  }

  ModelT m_;
  Data<S, MB, MD> d_;
  RootServo<S, MB, MD> root_servo_;
  VecQ q_, q_target_, q_prev_;
  VecV v_, v_target_, tau_user_, tau_, qdd_, v_prev_;
  std::array<Contact<S>, MaxContacts>& contacts() { return contact_buffers_[current_]; }
  const std::array<Contact<S>, MaxContacts>& contacts() const { return contact_buffers_[current_]; }
  std::array<std::array<Contact<S>, MaxContacts>, 2> contact_buffers_{};  // this step's, the previous step's
  int current_ = 0;
  int nc_ = 0, overflow_ = 0, passes_ = 0;
};

}  // namespace sparsebody::dynamics
