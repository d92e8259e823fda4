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
// propagated. The caller decides what to do (typically set_state() with a fresh pose and zero
// velocity, as Neural3Points' rollouts reset the character).
#pragma once
#include <algorithm>
#include <limits>
#include <ostream>

#include "sparsebody/dynamics/aba.hpp"
#include "sparsebody/dynamics/contact.hpp"
#include "sparsebody/dynamics/integrator.hpp"
#include "sparsebody/dynamics/pd_servo.hpp"

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

// PD servo on the free root toward the root entries of targets() (position p*, orientation R*) and
// target_velocities() (angular w*, linear v*, in the target's body frame: the layout of v), in the
// world frame:
//   F = clamp(kp_v (p* - p) + kd_v (R* v* - v+), max_force),  N = clamp(kp_w log(R* R^T) + kd_w (R* w* - w+), max_torque)
// with the damping evaluated at the next velocity (v+, w+) implicitly inside ABA (D_root = I^A + h K_r,
// aba.hpp), exactly like the joint servos' kd: a stiff root servo on the light pelvis is stable at
// h = 1/120, where the same gains explicit diverge. A block (force or torque) whose explicit part
// already exceeds its bound is applied as that bounded force alone (no implicit part); a block
// whose implicit part -h kd a takes it past the bound is re-solved that way (one more ABA solve on
// such steps), so the applied wrench never exceeds the bounds. The step reports the wrench it
// applied: root_servo_force() / root_servo_torque(). Used by Neural3Points' default controller as the
// residual wrench ("hand of God") that keeps the character balanced.
template <class S>
struct RootServo {
  bool enabled = false;
  S kp_linear = 0, kd_linear = 0;    // N/m, N s/m
  S kp_angular = 0, kd_angular = 0;  // N m/rad, N m s/rad
  S max_force = std::numeric_limits<S>::infinity();   // bound of |F| (N); 0: no force
  S max_torque = std::numeric_limits<S>::infinity();  // bound of |N| (N m); 0: no torque
};

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
  RootServo<S> root_servo;          // off by default; needs a free root

  explicit Simulator(const ModelT& model) : m_(model), d_(model) {
    for (int i = 0; i < m_.nb; ++i)
      if (m_.bodies[i].joint == JointType::Free) root_ = i;
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
  void set_state(const VecQ& q, const VecV& v) {
    q_ = q;
    v_ = v;
    refresh_kinematics();
  }
  // PD targets in the configuration layout (quaternions for spherical joints, angles for revolute).
  VecQ& targets() { return q_target_; }
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
  const Vec3<S>& root_servo_force() const { return root_force_; }
  const Vec3<S>& root_servo_torque() const { return root_torque_; }

  StepStatus step(S h) {
    const bool servo_root = root_servo.enabled && root_ >= 0;
    if (!q_.allFinite() || !v_.allFinite() || !tau_user_.allFinite() ||
        ((mode == ControlMode::PdTargets || servo_root) && (!q_target_.allFinite() || !v_target_.allFinite())))
      return StepStatus::NonFiniteInput;
    q_prev_ = q_;
    v_prev_ = v_;
    // Kinematics of the current state are already in d_ (from the previous step or set_state).
    velocity_product_forces(m_, d_);
    if (mode == ControlMode::PdTargets) pd_torques(m_, q_, v_, q_target_, v_target_, tau_);
    else passive_torques(m_, v_, tau_);
    tau_ += tau_user_;
    root_force_.setZero();
    root_torque_.setZero();
    const S hd = implicit_damping ? h : S(0);
    implicit_damping_diagonal(m_, hd, mode == ControlMode::PdTargets, d_.implicit_diagonal);
    if (servo_root) {
      root_servo_explicit();
      root_servo_implicit(hd);
    }
    if (contacts_enabled) {
      // Two buffers, flipped: the previous step's contacts stay readable for the warm start (see
      // detect_contacts) without copying them.
      const int prev = current_;
      current_ ^= 1;
      nc_ = detect_contacts(m_, d_, env, contact, contacts(), overflow_, contact_buffers_[prev].data(),
                           warm_start_contacts ? nc_ : 0);
    } else {
      nc_ = 0;
    }
    bool ok = true;
    passes_ = 0;
    // A root servo block whose implicit part took it past its bound is re-solved as that bound
    // alone (same contact assembly: one more ABA solve, only on such steps; at most two, as the
    // re-solve of one block changes the other's implicit part).
    auto bound_root_servo = [&] {
      for (int k = 0; k < 2 && ok && servo_root && root_servo_over_bound(hd); ++k) {
        root_servo_implicit(hd);
        ok = aba_solve(m_, d_, tau_, qdd_);
        ++passes_;
      }
    };
    if (nc_ == 0) {
      d_.has_ext = false;
      ok = aba_solve(m_, d_, tau_, qdd_);
      passes_ = 1;
      bound_root_servo();
    } else {
      const int max_passes = std::max(1, contact.max_passes);  // at least the one solve a step needs
      for (int pass = 0; pass < max_passes; ++pass) {
        assemble_contacts(m_, d_, contacts(), nc_, contact, h);
        ok = aba_solve(m_, d_, tau_, qdd_);
        ++passes_;
        if (!ok) break;
        if (!update_contact_set(m_, d_, contacts(), nc_, contact, h)) break;
      }
      bound_root_servo();
      d_.has_ext = false;
    }
    if (!ok) return rollback(StepStatus::SolverFailure);
    if (servo_root) {  // applied wrench: explicit part - h K_r qdd (body frame), to the world frame
      const int k = m_.bodies[root_].v_index;
      Vec6<S> w = root_w_;
      for (int r = 0; r < 6; ++r) w(r) -= hd * root_k_(r) * qdd_(k + r);
      root_torque_ = d_.R[root_] * w.template head<3>();
      root_force_ = d_.R[root_] * w.template tail<3>();
    }
    integrate(m_, q_, v_, qdd_, h);
    if (!q_.allFinite() || !v_.allFinite()) return rollback(StepStatus::NonFiniteResult);
    if (v_.cwiseAbs().maxCoeff() > velocity_limit) return rollback(StepStatus::VelocityLimit);
    forward_kinematics(m_, d_, q_, &v_);
    return StepStatus::Ok;
  }

 private:
  void refresh_kinematics() { forward_kinematics(m_, d_, q_, &v_); }

  // The root servo's explicit part (root_w_, body frame), added to tau_, and its implicit gains K_r.
  void root_servo_explicit() {
    const Body<S>& b = m_.bodies[root_];
    const RootServo<S>& c = root_servo;
    const Mat3<S>& R = d_.R[root_];
    const Quat<S> Rt = read_quat<S>(q_target_, b.q_index + 3).normalized();
    const Vec3<S> wt = Rt * Vec3<S>(v_target_.template segment<3>(b.v_index));
    const Vec3<S> vt = Rt * Vec3<S>(v_target_.template segment<3>(b.v_index + 3));
    const Vec3<S> w = R * Vec3<S>(v_.template segment<3>(b.v_index)), v = R * Vec3<S>(v_.template segment<3>(b.v_index + 3));
    Vec3<S> F = c.kp_linear * (Vec3<S>(q_target_.template segment<3>(b.q_index)) - d_.p[root_]) + c.kd_linear * (vt - v);
    Vec3<S> N = c.kp_angular * quat_log(Quat<S>(Rt * Quat<S>(R).conjugate())) + c.kd_angular * (wt - w);
    // Saturated block: the bounded force alone (its implicit damping would add to the bound).
    const S nf = F.norm(), nn = N.norm();
    const S max_f = std::max(c.max_force, S(0)), max_n = std::max(c.max_torque, S(0));
    const bool sat_f = !(nf <= max_f) || max_f == S(0), sat_n = !(nn <= max_n) || max_n == S(0);
    if (sat_f) F = nf > max_f ? Vec3<S>(F * (max_f / nf)) : Vec3<S>::Zero();
    if (sat_n) N = nn > max_n ? Vec3<S>(N * (max_n / nn)) : Vec3<S>::Zero();
    root_w_.template head<3>() = R.transpose() * N;
    root_w_.template tail<3>() = R.transpose() * F;
    root_k_.template head<3>().setConstant(sat_n ? S(0) : c.kd_angular);
    root_k_.template tail<3>().setConstant(sat_f ? S(0) : c.kd_linear);
    tau_.template segment<6>(b.v_index) += root_w_;
  }

  // The root servo's implicit damping h K_r on the root's entries of ABA's implicit diagonal.
  void root_servo_implicit(S hd) {
    const int k = m_.bodies[root_].v_index;
    for (int r = 0; r < 6; ++r) d_.implicit_diagonal(k + r) = hd * root_k_(r);
  }

  // After a solve: the applied root wrench root_w_ - h K_r qdd per block (torque, force); a block
  // over its bound becomes that bound in the applied direction, explicit (K_r block 0). True when
  // something changed (the caller re-solves).
  bool root_servo_over_bound(S hd) {
    const int k = m_.bodies[root_].v_index;
    bool changed = false;
    for (int blk = 0; blk < 2; ++blk) {
      const S bound = blk == 0 ? root_servo.max_torque : root_servo.max_force;
      const int o = 3 * blk;
      if (root_k_(o) == S(0)) continue;  // saturated already: explicit, bounded
      Vec3<S> w;
      for (int r = 0; r < 3; ++r) w(r) = root_w_(o + r) - hd * root_k_(o + r) * qdd_(k + o + r);
      const S n = w.norm();
      if (!(n > bound)) continue;
      const Vec3<S> wb = w * (bound / n);
      tau_.template segment<3>(k + o) += wb - Vec3<S>(root_w_.template segment<3>(o));
      root_w_.template segment<3>(o) = wb;
      root_k_.template segment<3>(o).setZero();
      changed = true;
    }
    return changed;
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
  VecQ q_, q_target_, q_prev_;
  VecV v_, v_target_, tau_user_, tau_, qdd_, v_prev_;
  std::array<Contact<S>, MaxContacts>& contacts() { return contact_buffers_[current_]; }
  const std::array<Contact<S>, MaxContacts>& contacts() const { return contact_buffers_[current_]; }
  std::array<std::array<Contact<S>, MaxContacts>, 2> contact_buffers_{};  // this step's, the previous step's
  int current_ = 0;
  int nc_ = 0, overflow_ = 0, passes_ = 0;
  int root_ = -1;
  Vec6<S> root_w_ = Vec6<S>::Zero(), root_k_ = Vec6<S>::Zero();  // root servo: explicit wrench, K_r
  Vec3<S> root_force_ = Vec3<S>::Zero(), root_torque_ = Vec3<S>::Zero();
};

}  // namespace sparsebody::dynamics
