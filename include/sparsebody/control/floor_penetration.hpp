// How far a body's lowest contact point is below the floor (y = 0): the kinematics' deepest
// contact sphere (dynamics::Model::points, centre p, radius r) gives max(0, -min_k (p_k.y - r_k)).
// The model-based controller lifts the predicted pose out of the floor by it (ground_lift), the
// physics pipeline reports it for the simulated body (penetration()).
#pragma once
#include <algorithm>

#include "sparsebody/dynamics/kinematics.hpp"

namespace sparsebody::control {

// >= 0 (m); a NaN point is ignored (it never compares lower), one at -inf gives +inf.
template <class S, int MB, int MD>
S floor_penetration(const dynamics::Model<S, MB, MD>& m, const dynamics::Data<S, MB, MD>& d) noexcept {
  S lo = 0;
  for (int k = 0; k < m.num_points; ++k) {
    const auto& pt = m.points[k];
    lo = std::min(lo, dynamics::point_position(d, pt.body, pt.pos).y() - pt.radius);
  }
  return -lo;
}

}  // namespace sparsebody::control
