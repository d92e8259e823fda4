// Root servo: a PD servo on the free root toward a reference pose and velocity, in the world frame:
//   F = clamp(kp_v (p* - p) + kd_v (v* - v+), max_force),  N = clamp(kp_w log(R* R^T) + kd_w (w* - w+), max_torque)
// Its damping acts on the next velocity (v+, w+), implicitly inside ABA like the joint servos' kd:
// h K_r, K_r = diag(kd_w 1_3, kd_v 1_3), goes on the root's entries of Data::implicit_diagonal
// (D_root = I^A + h K_r, aba.hpp). That is what makes a stiff servo on the light pelvis stable at
// h = 1/120, where the same gains explicit diverge. Bounds hold for the applied wrench: a block
// (force or torque) whose explicit part already exceeds its bound is applied as that bounded force
// alone (no implicit part); a block that the implicit part -h kd a takes past its bound is re-solved
// that way (rebound: one more ABA solve on such steps). Neural3Points' default controller uses it
// for the residual wrench ("hand of God") that keeps the character balanced.
#pragma once
#include <algorithm>
#include <limits>

#include "sparsebody/dynamics/kinematics.hpp"

namespace sparsebody::dynamics {

template <class S>
struct RootServoOptions {
  bool enabled = false;              // needs a free root
  S kp_linear = 0, kd_linear = 0;    // N/m, N s/m
  S kp_angular = 0, kd_angular = 0;  // N m/rad, N m s/rad
  S max_force = std::numeric_limits<S>::infinity();   // bound of |F| (N); 0: no force
  S max_torque = std::numeric_limits<S>::infinity();  // bound of |N| (N m); 0: no torque
};

// Pose and velocity of the root in the world frame (position p, orientation R, linear v, angular w).
template <class S>
struct RootMotion {
  Vec3<S> p, v, w;
  Quat<S> R;
};

// The PD law, unbounded, with the damping at the given velocities:
// F = kp_v (p* - p) + kd_v (v* - v),  N = kp_w log(R* R^T) + kd_w (w* - w).
template <class S>
inline void root_pd_wrench(const RootServoOptions<S>& o, const RootMotion<S>& now, const RootMotion<S>& ref, Vec3<S>& F,
                           Vec3<S>& N) {
  F = o.kp_linear * (ref.p - now.p) + o.kd_linear * (ref.v - now.v);
  N = o.kp_angular * quat_log(Quat<S>(ref.R * now.R.conjugate())) + o.kd_angular * (ref.w - now.w);
}

// One step of the servo on a model's free root: its explicit wrench and implicit gains, the bounds,
// and the report of what it applied. Fixed-size state, no allocation.
template <class S, int MB, int MD>
class RootServo {
 public:
  using ModelT = Model<S, MB, MD>;
  using VecQ = typename ModelT::VecQ;
  using VecV = typename ModelT::VecV;

  // root: the model's free-joint body, or -1 (the servo then never acts).
  explicit RootServo(int root = -1) : root_(root) {}
  bool available() const { return root_ >= 0; }

  // Explicit part, added to tau: the PD law at the current velocity, a saturated block replaced by
  // its bound. Targets in the layout of q / v (v*: the target's body frame, like v). Also sets K_r
  // (zero on a saturated block).
  void add_explicit(const RootServoOptions<S>& o, const ModelT& m, const Data<S, MB, MD>& d, const VecQ& q_target,
                    const VecV& v, const VecV& v_target, VecV& tau) {
    const Body<S>& b = m.bodies[root_];
    const Mat3<S>& R = d.R[root_];
    RootMotion<S> now, ref;
    now.p = d.p[root_];
    now.R = Quat<S>(R);
    now.w = R * Vec3<S>(v.template segment<3>(b.v_index));
    now.v = R * Vec3<S>(v.template segment<3>(b.v_index + 3));
    ref.p = q_target.template segment<3>(b.q_index);
    ref.R = read_quat<S>(q_target, b.q_index + 3).normalized();
    ref.w = ref.R * Vec3<S>(v_target.template segment<3>(b.v_index));
    ref.v = ref.R * Vec3<S>(v_target.template segment<3>(b.v_index + 3));
    Vec3<S> F, N;
    root_pd_wrench(o, now, ref, F, N);
    // Saturated block: the bounded force alone (its implicit damping would add to the bound).
    const S nf = F.norm(), nn = N.norm();
    const S max_f = std::max(o.max_force, S(0)), max_n = std::max(o.max_torque, S(0));
    const bool sat_f = !(nf <= max_f) || max_f == S(0), sat_n = !(nn <= max_n) || max_n == S(0);
    if (sat_f) F = nf > max_f ? Vec3<S>(F * (max_f / nf)) : Vec3<S>::Zero();
    if (sat_n) N = nn > max_n ? Vec3<S>(N * (max_n / nn)) : Vec3<S>::Zero();
    w_.template head<3>() = R.transpose() * N;
    w_.template tail<3>() = R.transpose() * F;
    k_.template head<3>().setConstant(sat_n ? S(0) : o.kd_angular);
    k_.template tail<3>().setConstant(sat_f ? S(0) : o.kd_linear);
    tau.template segment<6>(b.v_index) += w_;
  }

  // Implicit part: h K_r on the root's entries of ABA's implicit diagonal (hd = h, or 0 when the
  // simulation runs its damping explicitly).
  void write_implicit(const ModelT& m, S hd, VecV& diag) const {
    const int k = m.bodies[root_].v_index;
    for (int r = 0; r < 6; ++r) diag(k + r) = hd * k_(r);
  }

  // After a solve: the applied wrench w - h K_r qdd per block (torque, force); a block over its
  // bound becomes that bound in the applied direction, explicit (K_r block 0), and tau changes by
  // the difference. True when something changed (the caller writes the implicit part and re-solves).
  bool rebound(const RootServoOptions<S>& o, const ModelT& m, S hd, const VecV& qdd, VecV& tau) {
    const int k = m.bodies[root_].v_index;
    bool changed = false;
    for (int blk = 0; blk < 2; ++blk) {
      const S bound = blk == 0 ? o.max_torque : o.max_force;
      const int off = 3 * blk;
      if (k_(off) == S(0)) continue;  // saturated already: explicit, bounded
      Vec3<S> w;
      for (int r = 0; r < 3; ++r) w(r) = w_(off + r) - hd * k_(off + r) * qdd(k + off + r);
      const S n = w.norm();
      if (!(n > bound)) continue;
      const Vec3<S> wb = w * (bound / n);
      tau.template segment<3>(k + off) += wb - Vec3<S>(w_.template segment<3>(off));
      w_.template segment<3>(off) = wb;
      k_.template segment<3>(off).setZero();
      changed = true;
    }
    return changed;
  }

  // The wrench applied in the solved step, explicit part - h K_r qdd (body frame), in the world frame.
  void report(const ModelT& m, const Data<S, MB, MD>& d, S hd, const VecV& qdd) {
    const int k = m.bodies[root_].v_index;
    Vec6<S> w = w_;
    for (int r = 0; r < 6; ++r) w(r) -= hd * k_(r) * qdd(k + r);
    torque_ = d.R[root_] * w.template head<3>();
    force_ = d.R[root_] * w.template tail<3>();
  }
  void clear_report() {
    force_.setZero();
    torque_.setZero();
  }
  // World-frame wrench of the last report (zero when the servo did not act).
  const Vec3<S>& force() const { return force_; }
  const Vec3<S>& torque() const { return torque_; }

 private:
  int root_ = -1;
  Vec6<S> w_ = Vec6<S>::Zero(), k_ = Vec6<S>::Zero();  // explicit wrench (body frame: torque; force), K_r
  Vec3<S> force_ = Vec3<S>::Zero(), torque_ = Vec3<S>::Zero();
};

}  // namespace sparsebody::dynamics
