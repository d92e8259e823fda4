// LoBSTrBatch (avatar/lobstr_batch.hpp): N users stepped in one call equal N LoBSTrPipelines
// stepped one by one, bit for bit (pose, world positions, contacts, calibration), with the shipped
// compact weights in float, f16 and int8 storage, each user its own session (sizes, walking and
// standing, a lost tracker, a NaN burst, a restart). (Allocations: test_alloc.cpp.)
#include <doctest/doctest.h>

#include <cstring>
#include <limits>

#include "sparsebody/avatar/lobstr_batch.hpp"
#include "support/crowd_sessions.hpp"

using namespace sparsebody;

namespace {

template <class P>
void check_batch_equals_singles(int n) {
  const auto w = P::load(SPARSEBODY_LOBSTR_WEIGHTS);
  avatar::LoBSTrBatch<P> crowd(w, n);
  std::vector<std::unique_ptr<P>> single;
  std::vector<std::vector<trackers::TrackerFrame>> in;
  std::size_t len = 1 << 30;
  for (int u = 0; u < n; ++u) {
    single.push_back(std::make_unique<P>(w));
    in.push_back(sparsebody_test::crowd_user_frames(u % 6, true));
    len = std::min(len, in.back().size());
  }
  std::vector<trackers::TrackerFrame> frames(static_cast<std::size_t>(n));
  std::vector<char> restart(static_cast<std::size_t>(n), 0);
  int compared = 0;
  for (std::size_t t = 0; t < len; ++t) {
    for (int u = 0; u < n; ++u) {
      frames[u] = in[u][t];
      restart[u] = (u == 1 && t == 60);  // one user restarts mid-session
      single[u]->step(frames[u], restart[u] != 0);
    }
    bool r[64];
    for (int u = 0; u < n; ++u) r[u] = restart[u] != 0;
    crowd.step(frames.data(), r);
    for (int u = 0; u < n; ++u) {
      const P& a = *single[u];
      const P& b = crowd[u];
      REQUIRE(a.has_output() == b.has_output());
      if (!a.has_output()) continue;
      const auto& wa = a.world();
      const auto& wb = b.world();
      for (std::size_t j = 0; j < wa.position.size(); ++j) {
        REQUIRE(std::memcmp(wa.position[j].data(), wb.position[j].data(), sizeof(double) * 3) == 0);
        REQUIRE(std::memcmp(a.pose().local[j].coeffs().data(), b.pose().local[j].coeffs().data(), sizeof(double) * 4) == 0);
      }
      REQUIRE(a.contact_probability(0) == b.contact_probability(0));
      REQUIRE(a.contact_probability(1) == b.contact_probability(1));
      REQUIRE(a.calibration().scale == b.calibration().scale);
      ++compared;
    }
  }
  CHECK(compared > n * static_cast<int>(len) / 2);
  for (int u = 0; u < n; ++u) CHECK(crowd[u].calibration_report().status == features::CalibrationStatus::Calibrated);
}

}  // namespace

TEST_CASE("LoBSTr batch: N users in one call equal N pipelines stepped alone, bit for bit (float, f16, int8)") {
  check_batch_equals_singles<avatar::LoBSTrCompact>(7);
  check_batch_equals_singles<avatar::LoBSTrCompactF16>(5);
  check_batch_equals_singles<avatar::LoBSTrCompactQ8>(5);
  check_batch_equals_singles<avatar::LoBSTrCompact>(1);
}

TEST_CASE("LoBSTr batch: bad sizes and Window mode are refused at construction") {
  const auto w = avatar::LoBSTrCompact::load(SPARSEBODY_LOBSTR_WEIGHTS);
  CHECK_THROWS_AS(avatar::LoBSTrBatch<avatar::LoBSTrCompact>(w, 0), std::invalid_argument);
  CHECK_THROWS_AS(avatar::LoBSTrBatch<avatar::LoBSTrCompact>(w, 65), std::invalid_argument);
  avatar::LoBSTrConfig cfg;
  cfg.mode = avatar::RunMode::Window;
  CHECK_THROWS_AS(avatar::LoBSTrBatch<avatar::LoBSTrCompact>(w, 4, cfg), std::invalid_argument);
}
