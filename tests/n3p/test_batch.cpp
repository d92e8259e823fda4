// N3PBatch (avatar/n3p_batch.hpp): N users' Neural3Points direct mode stepped in one call equal N
// N3PPipelines stepped one by one, bit for bit (pose, world positions, calibration), with the
// shipped weights in float, f16 and int8 storage, each user its own session (sizes, walking and
// standing, a lost controller, a NaN burst, a restart). (Allocations: test_alloc.cpp.)
#include <doctest/doctest.h>

#include <cstring>
#include <limits>
#include <memory>

#include "sparsebody/avatar/n3p_batch.hpp"
#include "support/crowd_sessions.hpp"

using namespace sparsebody;

namespace {

template <class P>
void check_batch_equals_singles(int n) {
  const auto w = P::load(std::string(SPARSEBODY_SOURCE_DIR) + "/examples/weights/n3p");
  avatar::N3PBatch<P> crowd(w, n);
  std::vector<std::unique_ptr<P>> single;
  std::vector<std::vector<trackers::TrackerFrame>> in;
  std::size_t len = 1 << 30;
  for (int u = 0; u < n; ++u) {
    single.push_back(std::make_unique<P>(w));
    in.push_back(sparsebody_test::crowd_user_frames(u % 6, false));
    len = std::min(len, in.back().size());
  }
  std::vector<trackers::TrackerFrame> frames(static_cast<std::size_t>(n));
  bool restart[64] = {};
  int compared = 0;
  for (std::size_t t = 0; t < len; ++t) {
    for (int u = 0; u < n; ++u) {
      frames[u] = in[u][t];
      restart[u] = u == 1 && t == 60;  // one user restarts mid-session
      single[u]->step(frames[u], restart[u]);
    }
    crowd.step(frames.data(), restart);
    for (int u = 0; u < n; ++u) {
      const P& a = *single[u];
      const P& b = crowd[u];
      REQUIRE(a.has_output() == b.has_output());
      if (!a.has_output()) continue;
      for (std::size_t j = 0; j < a.world().position.size(); ++j) {
        REQUIRE(std::memcmp(a.world().position[j].data(), b.world().position[j].data(), sizeof(double) * 3) == 0);
        REQUIRE(std::memcmp(a.pose().local[j].coeffs().data(), b.pose().local[j].coeffs().data(), sizeof(double) * 4) == 0);
      }
      REQUIRE(a.calibration_report().scale == b.calibration_report().scale);
      ++compared;
    }
  }
  CHECK(compared > n * static_cast<int>(len) / 2);
}

}  // namespace

TEST_CASE("N3P batch: N users in one call equal N direct-mode pipelines stepped alone, bit for bit (float, f16, int8)") {
  check_batch_equals_singles<avatar::N3PDirect>(7);
  check_batch_equals_singles<avatar::N3PDirectF16>(5);
  check_batch_equals_singles<avatar::N3PDirectQ8>(5);
  check_batch_equals_singles<avatar::N3PDirect>(1);
}

TEST_CASE("N3P batch: sizes outside 1..64 are refused at construction") {
  const auto w = avatar::N3PDirect::load(std::string(SPARSEBODY_SOURCE_DIR) + "/examples/weights/n3p");
  CHECK_THROWS_AS(avatar::N3PBatch<avatar::N3PDirect>(w, 0), std::invalid_argument);
  CHECK_THROWS_AS(avatar::N3PBatch<avatar::N3PDirect>(w, 65), std::invalid_argument);
}
