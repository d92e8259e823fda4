// Sessions of several users for the batch tests (avatar/lobstr_batch.hpp, n3p_batch.hpp): user u
// gets its own eye height (1.45 + 0.07 u m), heading (0.3 u rad) and phases (standing or walking
// first, then stand, walk, stand) at 30 Hz; user 2 loses its right controller for a second,
// user 3 has a NaN burst on the headset.
#pragma once
#include <limits>
#include <vector>

#include "support/standing_stream.hpp"

namespace sparsebody_test {

inline std::vector<sparsebody::trackers::TrackerFrame> crowd_user_frames(int u, bool pelvis) {
  const double eye = 1.45 + 0.07 * u;
  auto f = session({{u % 2 ? Phase::Walk : Phase::Stand, 0.7 + 0.1 * u, eye}, {Phase::Stand, 2.0, eye}, {Phase::Walk, 2.0, eye},
                    {Phase::Stand, 1.0, eye}},
                   30.0, 0.3 * u, pelvis);
  if (u == 2)
    for (std::size_t i = 100; i < 130 && i < f.size(); ++i) f[i].valid[2] = false;
  if (u == 3)
    for (std::size_t i = 80; i < 84 && i < f.size(); ++i) f[i].pose[0].position.y = std::numeric_limits<float>::quiet_NaN();
  return f;
}

// Frames [from, to) of sessions `in` (one per user, at least `to` frames each) through each of
// the batches (LoBSTrBatch, N3PBatch, ...: size() == in.size() <= 64), user 4 restarting at
// frame 70. Allocates nothing itself (for the allocation tests).
template <class... Batches>
void step_crowds(const std::vector<std::vector<sparsebody::trackers::TrackerFrame>>& in, std::size_t from,
                 std::size_t to, Batches&... batches) {
  sparsebody::trackers::TrackerFrame frames[64];
  bool restart[64] = {};
  const int n = static_cast<int>(in.size());
  for (std::size_t t = from; t < to; ++t) {
    for (int u = 0; u < n; ++u) {
      frames[u] = in[static_cast<std::size_t>(u)][t];
      restart[u] = t == 70 && u == 4;
    }
    (batches.step(frames, restart), ...);
  }
}

}  // namespace sparsebody_test
