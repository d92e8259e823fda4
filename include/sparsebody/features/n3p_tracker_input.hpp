// Neural3Points tracker input o = {p_X, q_X}, X in {H, L, R} (SCA 2022, §4) expressed in a heading
// frame: inv(h) (x) o. Layout [p_H p_L p_R | q6_H q6_L q6_R] (features/n3p_state.hpp), 6D = columns
// [2, 1] of R_y(-theta) R_X. The inverse (from_local) turns a predicted o* back into world poses;
// its 6D is not orthonormal and is kept as is (the network was trained on that), orthonormalised
// only where a rotation is needed (pose::from6d).
#pragma once
#include <array>

#include <Eigen/Core>

#include "sparsebody/features/heading_frame.hpp"
#include "sparsebody/features/n3p_state.hpp"

namespace sparsebody::features::n3p {

// One tracker in world space: position and the two 6D columns (world), double precision.
struct TrackerSample {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Vector3d fwd = Eigen::Vector3d::UnitZ();  // R e_z
  Eigen::Vector3d up = Eigen::Vector3d::UnitY();   // R e_y

  static TrackerSample from(const Eigen::Vector3d& position, const Eigen::Matrix3d& R) noexcept {
    return {position, R.col(2), R.col(1)};
  }
  bool finite() const noexcept { return p.allFinite() && fwd.allFinite() && up.allFinite(); }
};
using TrackerSet = std::array<TrackerSample, kTrackers>;

// o in frame h -> out[0..26].
template <typename T>
inline void tracker_input(const HeadingFrame& h, const TrackerSet& o, T* out) noexcept {
  for (int k = 0; k < kTrackers; ++k) {
    const Eigen::Vector3d p = h.point_to_local(o[k].p);
    const Eigen::Vector3d a = h.vector_to_local(o[k].fwd), b = h.vector_to_local(o[k].up);
    for (int i = 0; i < 3; ++i) {
      out[kOPos + 3 * k + i] = static_cast<T>(p[i]);
      out[kORot + 6 * k + i] = static_cast<T>(a[i]);
      out[kORot + 6 * k + 3 + i] = static_cast<T>(b[i]);
    }
  }
}

// Tracker k of an o vector in frame h -> world sample.
template <typename T>
inline TrackerSample tracker_from_local(const HeadingFrame& h, const T* o, int k) noexcept {
  const T* p = o + kOPos + 3 * k;
  const T* q = o + kORot + 6 * k;
  TrackerSample s;
  s.p = h.point_to_world(Eigen::Vector3d(p[0], p[1], p[2]));
  s.fwd = h.vector_to_world(Eigen::Vector3d(q[0], q[1], q[2]));
  s.up = h.vector_to_world(Eigen::Vector3d(q[3], q[4], q[5]));
  return s;
}

}  // namespace sparsebody::features::n3p
