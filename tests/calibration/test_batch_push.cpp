// Many users' device streams through a batch (avatar/lobstr_batch.hpp, n3p_batch.hpp: push): each
// user's own resampling, recentre and controller-swap checks, then the users' networks together.
// Five users on the device session of the CMU clip 01_01 (72 Hz): as recorded, controllers in the
// other hands, a recentred tracking space from 6 s on, a 90 Hz clock, and a 24 Hz clock with a
// 0.6 s dropout (two ticks per frame, a restart). Every user equals a pipeline of its own pushed
// the same frames, bit for bit, float and int8, with no allocation.
#include <doctest/doctest.h>

#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "sparsebody/avatar/lobstr_batch.hpp"
#include "sparsebody/avatar/n3p_batch.hpp"
#define SPARSEBODY_ALLOC_COUNTER_USE_ONLY  // test_recenter.cpp defines the operators
#include "support/alloc_counter.hpp"
#include "support/device_session.hpp"

using namespace sparsebody;

namespace {

constexpr int kUsers = 5;

std::vector<std::vector<trackers::TrackerFrame>> user_streams() {
  const auto& s = sparsebody_test::device_session_01_01();
  std::vector<std::vector<trackers::TrackerFrame>> in(kUsers, s);
  for (auto& f : in[1]) {  // picked up the wrong way round
    std::swap(f.pose[1], f.pose[2]);
    std::swap(f.valid[1], f.valid[2]);
  }
  const Eigen::Quaterniond yaw(Eigen::AngleAxisd(1.2, Eigen::Vector3d::UnitY()));
  const Eigen::Vector3d shift(1.5, 0.0, -0.8);
  for (auto& f : in[2])
    if (f.time >= 6.0)
      for (auto& p : f.pose) {  // the user recentred the tracking space
        p.position = trackers::to_xr(Eigen::Vector3d(yaw * trackers::to_eigen(p.position) + shift));
        p.orientation = trackers::to_xr(Eigen::Quaterniond(yaw * trackers::to_eigen(p.orientation)));
      }
  for (auto& f : in[3]) f.time *= 72.0 / 90.0;
  for (auto& f : in[4]) f.time = f.time * 3.0 + (f.time >= 2.0 ? 0.6 : 0.0);
  return in;
}

template <class P>
void require_equal(const P& a, const P& b) {
  REQUIRE(a.has_output() == b.has_output());
  REQUIRE(a.frames() == b.frames());
  REQUIRE(a.recentres() == b.recentres());
  REQUIRE(a.controller_swaps() == b.controller_swaps());
  if (!a.has_output()) return;
  for (std::size_t j = 0; j < a.world().position.size(); ++j) {
    CAPTURE(j);
    CAPTURE((a.world().position[j] - b.world().position[j]).norm());
    REQUIRE(std::memcmp(a.world().position[j].data(), b.world().position[j].data(), sizeof(double) * 3) == 0);
    REQUIRE(std::memcmp(a.pose().local[j].coeffs().data(), b.pose().local[j].coeffs().data(), sizeof(double) * 4) == 0);
  }
}

template <class Batch, class P, class W>
void check_push(const W& w) {
  const auto in = user_streams();
  Batch crowd(w, kUsers);
  std::vector<std::unique_ptr<P>> single;
  for (int u = 0; u < kUsers; ++u) single.push_back(std::make_unique<P>(w));
  trackers::TrackerFrame frames[kUsers];
  int two_ticks = 0;
  for (std::size_t t = 0; t < in[0].size(); ++t) {
    int ticks = 0;
    for (int u = 0; u < kUsers; ++u) {
      frames[u] = in[u][t];
      const int k = single[u]->push(frames[u]);
      ticks += k;
      two_ticks += k > 1;
    }
    REQUIRE(crowd.push(frames) == ticks);
    for (int u = 0; u < kUsers; ++u) {
      CAPTURE(u);
      CAPTURE(t);
      require_equal(*single[u], crowd[u]);
    }
  }
  CHECK(two_ticks > 100);
  CHECK(crowd[0].controller_swaps() == 0);
  CHECK(crowd[0].recentres() == 0);
  CHECK(crowd[1].controller_swaps() == 1);
  CHECK(crowd[2].recentres() == 1);
  for (int u = 0; u < kUsers; ++u) CHECK(crowd[u].has_output());

  // Again from a reset, counting allocations.
  for (int u = 0; u < kUsers; ++u) crowd[u].reset();
  sparsebody_test::AllocationCounter c;
  for (std::size_t t = 0; t < in[0].size(); ++t) {
    for (int u = 0; u < kUsers; ++u) frames[u] = in[u][t];
    crowd.push(frames);
  }
  CHECK(c.count() == 0);
  CHECK(crowd[1].controller_swaps() == 2);  // counted since construction
}

}  // namespace

TEST_CASE("a LoBSTr batch takes each user's device stream as that user's own pipeline does (float, int8)") {
  const std::string f = std::string(SPARSEBODY_WEIGHTS_DIR) + "/lobstr_compact.weights.json";
  check_push<avatar::LoBSTrBatch<avatar::LoBSTrCompact>, avatar::LoBSTrCompact>(avatar::LoBSTrCompact::load(f));
  check_push<avatar::LoBSTrBatch<avatar::LoBSTrCompactQ8>, avatar::LoBSTrCompactQ8>(avatar::LoBSTrCompactQ8::load(f));
}

TEST_CASE("a Neural3Points batch takes each user's device stream as that user's own pipeline does (float, int8)") {
  const std::string d = std::string(SPARSEBODY_WEIGHTS_DIR) + "/n3p";
  check_push<avatar::N3PBatch<avatar::N3PDirect>, avatar::N3PDirect>(avatar::N3PDirect::load(d));
  check_push<avatar::N3PBatch<avatar::N3PDirectQ8>, avatar::N3PDirectQ8>(avatar::N3PDirectQ8::load(d));
}
