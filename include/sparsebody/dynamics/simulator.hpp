// The simulation step: PD servos or direct torques, ground/box contact, ABA with implicit damping,
// semi-implicit Euler. Everything it touches is a fixed-size member, so step() never allocates,
// and it never throws.
//
// State layout: q (nq) and v (nv) as described in joint.hpp; body poses/velocities of the current
// state are in data() after every step (R[i], p[i]: world orientation/position of body i's joint
// frame; v[i]: body-frame spatial velocity).
//
// Recovery: step() checks its input and its result. Non-finite numbers, or any |v_k| above
// `velocity_limit`, make it restore the pre-step state and return the failure status; nothing is
// propagated. The caller decides what to do (typically setState() with a fresh pose and zero
// velocity, as Neural3Points' rollouts reset the character).
#pragma once
#include <ostream>

#include "aba.hpp"
#include "contact.hpp"
#include "integrator.hpp"
#include "pd_servo.hpp"

namespace sparsebody::dynamics {

enum class StepStatus : unsigned char {
  Ok = 0,
  NonFiniteInput,    // q, v, torques or targets contained NaN/Inf; nothing was done
  NonFiniteResult,   // the new state was not finite; rolled back
  VelocityLimit,     // |v_k| > velocity_limit after the step; rolled back
  SolverFailure,     // a joint-space inertia term was not positive definite; rolled back
};
inline const char* statusName(StepStatus s) {
  switch (s) {
    case StepStatus::Ok: return "ok";
    case StepStatus::NonFiniteInput: return "non-finite input";
    case StepStatus::NonFiniteResult: return "non-finite result";
    case StepStatus::VelocityLimit: return "velocity limit exceeded";
    default: return "solver failure";
  }
}

inline std::ostream& operator<<(std::ostream& os, StepStatus s) { return os << statusName(s); }

enum class ControlMode : unsigned char {
  PdTargets,  // Neural3Points: tau = PD(q_target) + tau_user, servo damping implicit
  Torque,     // QuestSim: tau = tau_user, only passive joint damping implicit
};

template <class S, int MB, int MD, int MaxContacts = 64, int MaxBoxes = 8>
class Simulator {
 public:
  using ModelT = Model<S, MB, MD>;
  using VecQ = typename ModelT::VecQ;
  using VecV = typename ModelT::VecV;

  // Settings (may be changed between steps).
  ControlMode mode = ControlMode::PdTargets;
  bool implicit_damping = true;     // false: explicit servo damping (for comparison only)
  S velocity_limit = S(500);        // rad/s or m/s on any coordinate
  ContactParams<S> contact;
  Environment<S, MaxBoxes> env;
  bool contacts_enabled = true;
  bool warm_start_contacts = true;  // sliding contacts start from last step's damper (fewer solver passes)

  explicit Simulator(const ModelT& model) : m_(model), d_(model) {
    q_ = m_.neutralConfiguration();
    v_.setZero(m_.nv);
    q_target_ = q_;
    v_target_.setZero(m_.nv);
    tau_user_.setZero(m_.nv);
    tau_.setZero(m_.nv);
    qdd_.setZero(m_.nv);
    q_prev_ = q_;
    v_prev_ = v_;
    env.ground_normal = -m_.gravity.normalized();
    refreshKinematics();
  }

  const ModelT& model() const { return m_; }
  const Data<S, MB, MD>& data() const { return d_; }
  const VecQ& q() const { return q_; }
  const VecV& v() const { return v_; }
  const VecV& lastAcceleration() const { return qdd_; }
  void setState(const VecQ& q, const VecV& v) {
    q_ = q;
    v_ = v;
    refreshKinematics();
  }
  // PD targets in the configuration layout (quaternions for spherical joints, angles for revolute).
  VecQ& targets() { return q_target_; }
  VecV& targetVelocities() { return v_target_; }
  // Generalised torques added in both modes (free root entries: body-frame wrench).
  VecV& torques() { return tau_user_; }
  // Convenience: target of one spherical joint (joint-frame rotation, child relative to parent).
  void setTarget(int body, const Quat<S>& rot) {
    const int k = m_.bodies[body].q_index;
    q_target_(k) = rot.w(); q_target_(k + 1) = rot.x(); q_target_(k + 2) = rot.y(); q_target_(k + 3) = rot.z();
  }
  void setTarget(int body, S angle) { q_target_(m_.bodies[body].q_index) = angle; }

  int numContacts() const { return nc_; }
  int numActiveContacts() const {
    int n = 0;
    for (int k = 0; k < nc_; ++k) n += contacts()[k].active ? 1 : 0;
    return n;
  }
  const Contact<S>& contactAt(int k) const { return contacts()[k]; }
  int contactOverflow() const { return overflow_; }
  int lastPasses() const { return passes_; }

  StepStatus step(S h) {
    if (!q_.allFinite() || !v_.allFinite() || !tau_user_.allFinite() ||
        (mode == ControlMode::PdTargets && (!q_target_.allFinite() || !v_target_.allFinite())))
      return StepStatus::NonFiniteInput;
    q_prev_ = q_;
    v_prev_ = v_;
    // Kinematics of the current state are already in d_ (from the previous step or setState).
    for (int i = 0; i < m_.nb; ++i) d_.bias[i] = crossForce(d_.v[i], mul6v(m_.bodies[i].I, d_.v[i]));
    if (mode == ControlMode::PdTargets) pdTorques(m_, q_, v_, q_target_, v_target_, tau_);
    else passiveTorques(m_, v_, tau_);
    tau_ += tau_user_;
    const S hd = implicit_damping ? h : S(0);
    const bool with_kd = mode == ControlMode::PdTargets;
    if (contacts_enabled) {
      // Two buffers, flipped: the previous step's contacts stay readable for the warm start (see
      // detectContacts) without copying them.
      const int prev = current_;
      current_ ^= 1;
      nc_ = detectContacts(m_, d_, env, contact, contacts(), overflow_, contact_buffers_[prev].data(),
                           warm_start_contacts ? nc_ : 0);
    } else {
      nc_ = 0;
    }
    bool ok = true;
    passes_ = 0;
    if (nc_ == 0) {
      d_.has_ext = false;
      ok = abaSolve(m_, d_, tau_, qdd_, hd, with_kd);
      passes_ = 1;
    } else {
      for (int pass = 0; pass < contact.max_passes; ++pass) {
        assembleContacts(m_, d_, contacts(), nc_, contact, h);
        ok = abaSolve(m_, d_, tau_, qdd_, hd, with_kd);
        ++passes_;
        if (!ok) break;
        if (!updateContactSet(m_, d_, contacts(), nc_, contact, h)) break;
      }
      d_.has_ext = false;
    }
    if (!ok) return rollback(StepStatus::SolverFailure);
    integrate(m_, q_, v_, qdd_, h);
    if (!q_.allFinite() || !v_.allFinite()) return rollback(StepStatus::NonFiniteResult);
    if (v_.cwiseAbs().maxCoeff() > velocity_limit) return rollback(StepStatus::VelocityLimit);
    forwardKinematics(m_, d_, q_, &v_);
    return StepStatus::Ok;
  }

 private:
  void refreshKinematics() { forwardKinematics(m_, d_, q_, &v_); }
  StepStatus rollback(StepStatus s) {
    q_ = q_prev_;
    v_ = v_prev_;
    d_.has_ext = false;
    refreshKinematics();
    return s;
  }

  ModelT m_;
  Data<S, MB, MD> d_;
  VecQ q_, q_target_, q_prev_;
  VecV v_, v_target_, tau_user_, tau_, qdd_, v_prev_;
  std::array<Contact<S>, MaxContacts>& contacts() { return contact_buffers_[current_]; }
  const std::array<Contact<S>, MaxContacts>& contacts() const { return contact_buffers_[current_]; }
  std::array<std::array<Contact<S>, MaxContacts>, 2> contact_buffers_{};  // this step's, the previous step's
  int current_ = 0;
  int nc_ = 0, overflow_ = 0, passes_ = 0;
};

}  // namespace sparsebody::dynamics
