// A learned correction of the Neural3Points model-based controller's PD targets (issue 14 item 4,
// the fallback to the paper's full policy pi of §5): every 30 Hz frame,
//   s = {x, g_F+1, g_F+2, g_F+3}   (control/n3p_policy_input.hpp's layout, 1008 values)
//   a = pi_c(s) in [-1, 1]^48      (MLP 1008-256-256-48, tanh on every layer: networks/policy_nets.hpp)
//   u = q_ref(F + lead) (+) action_scale a    (spherical joints Q exp(delta), hinges theta + delta)
// where F is the frame the character reaches in this frame's substeps, x the simulated character
// before them and g the reference frames after F, all in the heading of the reference at F (its
// root's forward on the floor). The model-based controller's feed-forward, stance support,
// velocity targets and residual wrench stay as they are.
// One function builds s for the training environment (training/n3p_env.hpp) and the pipeline
// (avatar/n3p_physics.hpp), so a policy trained there sees the same numbers here.
// No allocation after construction, no exception per frame.
#pragma once
#include <array>
#include <cmath>
#include <memory>
#include <string>

#include "sparsebody/control/n3p_policy_input.hpp"
#include "sparsebody/control/n3p_sim_retarget.hpp"
#include "sparsebody/core/error.hpp"
#include "sparsebody/dynamics/kinematics.hpp"
#include "sparsebody/features/heading_frame.hpp"
#include "sparsebody/networks/policy_nets.hpp"
#include "sparsebody/nn/network.hpp"

namespace sparsebody::control {

namespace n3p_correction {

// s from the simulated character (sim: world kinematics with velocities, the simulator's data) and
// the reference frames F .. F+3 (world kinematics of q_ref with the finite-difference velocity
// q_ref(k-1) -> q_ref(k)). Non-finite values are written as 0.
template <class T, class S, int MB, int MD>
inline void write_input(const N3PSimRetarget<S, MB, MD>& rt, const dynamics::Data<S, MB, MD>& sim,
                        const std::array<const dynamics::Data<S, MB, MD>*, 4>& ref, T* out) noexcept {
  namespace pol = n3p_policy;
  Eigen::Vector3d p, v;
  Eigen::Matrix3d R;
  rt.joint_state(*ref[0], 0, p, v, R);
  const features::HeadingFrame href = features::HeadingFrame::from(p, R.col(2));
  auto block = [&](const dynamics::Data<S, MB, MD>& d, T* o) {
    for (int j = 0; j < pol::kJoints; ++j) {
      rt.joint_state(d, j, p, v, R);
      pol::joint_block(href, p, v, Eigen::Vector3d(R.col(2)), Eigen::Vector3d(R.col(1)), o, j);
    }
  };
  block(sim, out);
  for (int k = 1; k <= pol::kFuture; ++k) block(*ref[k], out + pol::kBlock * k);
  for (int i = 0; i < pol::kPolicyIn; ++i)
    if (!std::isfinite(out[i])) out[i] = T(0);
}

// u = target (+) scale clamp(a): a has one entry per internal DoF (the velocity layout after the
// free root's 6); non-finite entries count as 0. Hinges theta + delta, ball joints Q exp(delta)
// (body frame, as dynamics::integrate), renormalised; a joint whose delta is zero is left as it
// is, so a = 0 gives the target bit for bit. delta: scratch of size nv (the deltas, for callers).
template <class T, class S, int MB, int MD>
inline void apply(const dynamics::Model<S, MB, MD>& m, const T* a, double scale, typename dynamics::Model<S, MB, MD>::VecV& delta,
                  typename dynamics::Model<S, MB, MD>::VecQ& u) noexcept {
  delta.setZero();
  for (int j = 0; j + 6 < m.nv; ++j) {
    const double x = std::isfinite(double(a[j])) ? std::fmin(1.0, std::fmax(-1.0, double(a[j]))) : 0.0;
    delta(6 + j) = S(scale * x);
  }
  for (int i = 0; i < m.nb; ++i) {
    const dynamics::Body<S>& b = m.bodies[i];
    if (b.joint == dynamics::JointType::Revolute) {
      u(b.q_index) += delta(b.v_index);
    } else if (b.joint == dynamics::JointType::Spherical) {
      const dynamics::Vec3<S> w = delta.template segment<3>(b.v_index);
      if (w.isZero(S(0))) continue;
      dynamics::Quat<S> Q = dynamics::read_quat<S>(u, b.q_index) * dynamics::quat_exp(w);
      Q.normalize();
      u(b.q_index) = Q.w();
      u(b.q_index + 1) = Q.x();
      u(b.q_index + 2) = Q.y();
      u(b.q_index + 3) = Q.z();
    }
  }
}

}  // namespace n3p_correction

// The run-time side: the trained network (weights shared between pipelines) and its scratch.
// JointDofs: the avatar's internal DoFs (48 for character::default_avatar).
template <typename T, class S, int MB, int MD, int JointDofs, typename W = T>
class N3PTargetCorrection {
 public:
  using Net = networks::N3PCorrectionNet<T, n3p_policy::kPolicyIn, JointDofs, W>;
  using Weights = nn::NetworkWeights<Net>;
  using ModelT = dynamics::Model<S, MB, MD>;
  using DataT = dynamics::Data<S, MB, MD>;
  using VecQ = typename ModelT::VecQ;
  using VecV = typename ModelT::VecV;

  // The exported policy (weights_tool.questsim.train --task n3p): kind "n3p_correction_policy", its
  // meta.action_scale (rad per unit output) required. Throws LoadError naming the file otherwise.
  static std::shared_ptr<const Weights> load(const std::string& path) {
    auto w = Weights::load(path, networks::kN3PCorrectionPolicyKind);
    action_scale_of(*w);
    return w;
  }
  // The same from the text of such a file (`source` names it in messages).
  static std::shared_ptr<const Weights> parse(const std::string& text, const std::string& source) {
    auto w = Weights::from_string(text, networks::kN3PCorrectionPolicyKind, source);
    action_scale_of(*w);
    return w;
  }
  static double action_scale_of(const Weights& w) {
    const auto& meta = w.info().meta;
    if (!meta.contains("action_scale") || !meta["action_scale"].is_number())
      throw LoadError(w.info().source, "meta.action_scale (rad per unit output) is missing");
    const double s = meta["action_scale"].template get<double>();
    if (!(s > 0 && s <= 1.0)) throw LoadError(w.info().source, "meta.action_scale " + std::to_string(s) + " is not in (0, 1] rad");
    return s;
  }

  N3PTargetCorrection(std::shared_ptr<const Weights> w, const ModelT& m)
      : scale_(action_scale_of(*w)), net_(std::move(w)), d_{DataT(m), DataT(m), DataT(m), DataT(m)} {
    if (m.nv - 6 != JointDofs) throw std::invalid_argument("N3PTargetCorrection: the avatar's joint DoFs differ from the policy's");
    v_.setZero(m.nv);
    delta_.setZero(m.nv);
  }

  // ref[k]: q_ref(F - 1 + k), k = 0..4 (F - 1 for the velocity of F); u: q_ref(F + lead) in, corrected out.
  // False (u unchanged) when the network's output is not finite.
  bool correct(const ModelT& m, const N3PSimRetarget<S, MB, MD>& rt, const DataT& sim, const std::array<const VecQ*, 5>& ref,
               VecQ& u) noexcept {
    for (int k = 0; k < 4; ++k) {
      N3PSimRetarget<S, MB, MD>::velocity(m, *ref[k], *ref[k + 1], S(1.0 / 30), v_);
      dynamics::forward_kinematics(m, d_[k], *ref[k + 1], &v_, true);
    }
    n3p_correction::write_input<T>(rt, sim, {&d_[0], &d_[1], &d_[2], &d_[3]}, s_.data());
    const T* a = net_.step(s_.data());
    for (int j = 0; j < JointDofs; ++j)
      if (!std::isfinite(a[j])) return false;
    n3p_correction::apply(m, a, scale_, delta_, u);
    return true;
  }

  double action_scale() const noexcept { return scale_; }
  const std::array<T, n3p_policy::kPolicyIn>& input() const noexcept { return s_; }

 private:
  double scale_;
  nn::Network<Net> net_;
  std::array<DataT, 4> d_;
  VecV v_, delta_;
  std::array<T, n3p_policy::kPolicyIn> s_{};
};

}  // namespace sparsebody::control
