// The residual root wrench of the Neural3Points model-based controller (model_based_controller.hpp):
// the non-physical help that keeps the character balanced, reported every simulation step (its
// size) and summed over a run (ResidualStats), so users see how much help was needed.
#pragma once
#include <algorithm>

namespace sparsebody::control {

// Size of the residual wrench of one step (N, N m).
struct ResidualWrench {
  double force = 0, torque = 0;
};

// Running statistics of the residual wrench over simulation steps (N, N m).
struct ResidualStats {
  double force_sum = 0, torque_sum = 0, force_max = 0, torque_max = 0;
  long long steps = 0;
  double force_mean() const noexcept { return steps ? force_sum / steps : 0; }
  double torque_mean() const noexcept { return steps ? torque_sum / steps : 0; }

  void add(const ResidualWrench& w) noexcept {
    force_sum += w.force;
    torque_sum += w.torque;
    force_max = std::max(force_max, w.force);
    torque_max = std::max(torque_max, w.torque);
    ++steps;
  }
  // The statistics of two runs together.
  void merge(const ResidualStats& o) noexcept {
    force_sum += o.force_sum;
    torque_sum += o.torque_sum;
    force_max = std::max(force_max, o.force_max);
    torque_max = std::max(torque_max, o.torque_max);
    steps += o.steps;
  }
};

}  // namespace sparsebody::control
