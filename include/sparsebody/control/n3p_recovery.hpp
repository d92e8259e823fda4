// Recovery of the Neural3Points physics mode's simulated character (§9: the character can fall
// where the controller fails; the system must recover), and its counts:
//   - a (re)start places the character at rest on the start frame's reference;
//   - a failed simulation step (rolled back by the simulator) or a fall (FallDetector: the
//     simulated root against the reference root, once per frame) places it on the reference of
//     the frame being tracked with the reference velocity (the finite difference from the frame
//     before; zero if not finite), and clears the controller's and the detector's state;
//   - placing lifts the reference out of the floor first with ModelBasedControllerConfig::
//     ground_resets (ModelBasedController::ground_lift), so the character does not start in it.
// Per call: no allocation, no exception.
#pragma once
#include <array>

#include "sparsebody/control/fall_detector.hpp"
#include "sparsebody/control/model_based_controller.hpp"
#include "sparsebody/control/n3p_sim_retarget.hpp"
#include "sparsebody/dynamics/simulator.hpp"

namespace sparsebody::control {

template <class S, int MB, int MD>
class N3PRecovery {
 public:
  using ModelT = dynamics::Model<S, MB, MD>;
  using VecQ = typename ModelT::VecQ;
  using VecV = typename ModelT::VecV;
  using Sim = dynamics::Simulator<S, MB, MD>;
  using Controller = ModelBasedController<S, MB, MD>;

  // root_body: the model's free root (its q entries: position, then the quaternion w, x, y, z).
  N3PRecovery(const ModelT& m, int root_body, FallDetectorConfig fall, bool ground_resets)
      : fall_(fall), q_place_(m.neutral_configuration()), root_(root_body), q_root_(m.bodies[root_body].q_index),
        ground_resets_(ground_resets) {
    v_.setZero(m.nv);
  }

  // Clears the detector and the counts.
  void reset() noexcept {
    fall_.reset();
    falls_ = sim_failures_ = restarts_ = 0;
    falls_by_.fill(0);
  }

  // A (re)start on configuration q, at rest.
  void start(const ModelT& m, Sim& sim, Controller& c, const VecQ& q) noexcept {
    v_.setZero();
    place(m, sim, c, q, v_);
    fall_.reset();
    ++restarts_;
  }

  // A failed step: the character on the reference q (q_prev the frame before).
  void after_failure(const ModelT& m, Sim& sim, Controller& c, const VecQ& q_prev, const VecQ& q) noexcept {
    ++sim_failures_;
    reset_on(m, sim, c, q_prev, q);
  }

  // The fall check of a frame against its reference q; a fall resets the character onto it.
  FallReason check(const ModelT& m, Sim& sim, Controller& c, const VecQ& q_prev, const VecQ& q) noexcept {
    const auto& d = sim.data();
    const int k = q_root_;
    const Eigen::Quaterniond Rr(double(q(k + 3)), double(q(k + 4)), double(q(k + 5)), double(q(k + 6)));
    const FallReason why =
        fall_.update(d.p[root_].template cast<double>(), d.R[root_].col(1).template cast<double>().normalized(),
                     Eigen::Vector3d(double(q(k)), double(q(k + 1)), double(q(k + 2))), (Rr.normalized() * Eigen::Vector3d::UnitY()).normalized());
    if (why != FallReason::None) {
      ++falls_;
      ++falls_by_[static_cast<int>(why)];
      reset_on(m, sim, c, q_prev, q);
    }
    return why;
  }

  long long falls() const noexcept { return falls_; }  // fall resets
  long long falls(FallReason why) const noexcept { return falls_by_[static_cast<int>(why)]; }
  long long sim_failures() const noexcept { return sim_failures_; }  // rolled-back steps -> reset
  long long restarts() const noexcept { return restarts_; }          // (re)starts

 private:
  void reset_on(const ModelT& m, Sim& sim, Controller& c, const VecQ& q_prev, const VecQ& q) noexcept {
    N3PSimRetarget<S, MB, MD>::velocity(m, q_prev, q, S(1.0 / 30), v_);
    if (!v_.allFinite()) v_.setZero();
    place(m, sim, c, q, v_);
    c.reset();
    fall_.reset();
  }

  // The character in configuration q (lifted out of the floor with ground_resets), velocity v.
  void place(const ModelT& m, Sim& sim, Controller& c, const VecQ& q, const VecV& v) noexcept {
    q_place_ = q;
    if (ground_resets_) q_place_(q_root_ + 1) += c.ground_lift(m, q_place_);
    sim.set_state(q_place_, v);
  }

  FallDetector<double> fall_;
  VecQ q_place_;
  VecV v_;
  int root_ = 0, q_root_ = 0;
  bool ground_resets_ = true;
  long long falls_ = 0, sim_failures_ = 0, restarts_ = 0;
  std::array<long long, 4> falls_by_{};
};

}  // namespace sparsebody::control
