// Crowds through the C API (sb_crowd_*: avatar/lobstr_batch.hpp, n3p_batch.hpp behind one handle):
// every user equals a pipeline of its own (sb_pipeline_create, same config, same frames) bit for
// bit, through controllers in the other hands, a 90 Hz clock, a tracking gap and repeated frames;
// push and read allocate nothing; every bad argument gets its status and a message naming it.
#include <doctest/doctest.h>

#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "capi_session.hpp"
#include "sparsebody/c/sparsebody.h"
#define SPARSEBODY_ALLOC_COUNTER_USE_ONLY  // test_capi.cpp defines the operators
#include "support/alloc_counter.hpp"

namespace {

const std::string kWeights = SPARSEBODY_WEIGHTS_DIR;
constexpr int kUsers = 4;

sb_weights* weights(int kind) {
  static sb_weights* lobstr = nullptr;
  static sb_weights* n3p = nullptr;
  sb_weights*& w = kind == SB_PIPELINE_LOBSTR ? lobstr : n3p;
  if (!w) w = capi_test::shipped_weights(kWeights, kind, SB_STORAGE_FLOAT);
  REQUIRE(w);
  return w;
}

sb_pipeline_config config(int kind) {
  sb_pipeline_config c;
  REQUIRE(sb_pipeline_config_init(&c, kind) == SB_OK);
  return c;
}

// User u's frames: the C API tests' device session as recorded (0), with the controllers in the
// other hands (1), on a 90 Hz clock (2), with a 1 s tracking gap at 4 s (3).
std::vector<std::vector<sb_tracker_frame>> user_frames() {
  static const auto s = capi_test::device_session(SPARSEBODY_TEST_CLIP);
  std::vector<std::vector<sb_tracker_frame>> in(kUsers);
  for (const auto& f : s)
    for (int u = 0; u < kUsers; ++u) in[u].push_back(capi_test::to_c(f));
  for (auto& f : in[1]) {
    std::swap(f.pose[1], f.pose[2]);
    const std::uint32_t l = (f.valid >> 1) & 1u, r = (f.valid >> 2) & 1u;
    f.valid = (f.valid & ~6u) | (r << 1) | (l << 2);
  }
  for (auto& f : in[2]) f.time *= 72.0 / 90.0;
  for (auto& f : in[3])
    if (f.time > 4.0) f.time += 1.0;
  return in;
}

bool same_bits(const void* a, const void* b, std::size_t n) { return std::memcmp(a, b, n) == 0; }

void check_crowd_equals_pipelines(int kind, int storage = SB_STORAGE_FLOAT) {
  const auto in = user_frames();
  const sb_pipeline_config cfg = config(kind);
  sb_weights* w = weights(kind);
  sb_weights* stored = nullptr;
  if (storage != SB_STORAGE_FLOAT) {
    stored = capi_test::shipped_weights(kWeights, kind, storage);
    REQUIRE(stored);
    w = stored;
  }
  sb_crowd* crowd = nullptr;
  REQUIRE(sb_crowd_create(w, &cfg, kUsers, &crowd) == SB_OK);
  int32_t size = 0;
  REQUIRE(sb_crowd_size(crowd, &size) == SB_OK);
  CHECK(size == kUsers);
  sb_pipeline* single[kUsers];
  sb_pipeline* user[kUsers];
  for (int u = 0; u < kUsers; ++u) {
    REQUIRE(sb_pipeline_create(w, &cfg, &single[u]) == SB_OK);
    REQUIRE(sb_crowd_user(crowd, u, &user[u]) == SB_OK);
  }
  int32_t n = 0;
  REQUIRE(sb_pipeline_joint_count(user[0], &n) == SB_OK);
  std::vector<sb_quatf> ra(n), rb(n);
  std::vector<sb_vec3f> pa(n), pb(n);
  sb_pose_info ia{}, ib{};
  ia.struct_size = ib.struct_size = sizeof ia;
  sb_tracker_frame frames[kUsers];
  long compared = 0, resets = 0;
  for (std::size_t t = 0; t < in[0].size(); ++t) {
    int32_t want[kUsers], got[kUsers];
    for (int u = 0; u < kUsers; ++u) {
      frames[u] = in[u][t];
      REQUIRE(sb_pipeline_push(single[u], &frames[u], &want[u]) >= 0);
    }
    REQUIRE(sb_crowd_push(crowd, frames, kUsers, got) >= 0);
    if (t % 50 == 0) {  // no new frame for anyone: the same frames again complete no tick
      int32_t again[kUsers];
      REQUIRE(sb_crowd_push(crowd, frames, kUsers, again) >= 0);
      for (int u = 0; u < kUsers; ++u) CHECK(again[u] == 0);
    }
    for (int u = 0; u < kUsers; ++u) {
      CAPTURE(u);
      CAPTURE(t);
      if (t % 50 != 0) REQUIRE(got[u] == want[u]);
      const sb_status sa = sb_pipeline_read(single[u], &ia, ra.data(), pa.data(), n);
      const sb_status sbs = sb_pipeline_read(user[u], &ib, rb.data(), pb.data(), n);
      REQUIRE(sa == sbs);
      if (t % 50 != 0) REQUIRE(ia.flags == ib.flags);  // the repeat reports no reset
      resets += (ib.flags & SB_POSE_RESET) != 0;
      REQUIRE(ia.frames == ib.frames);
      if (sa != SB_OK) continue;
      REQUIRE(same_bits(ra.data(), rb.data(), sizeof(sb_quatf) * n));
      REQUIRE(same_bits(pa.data(), pb.data(), sizeof(sb_vec3f) * n));
      REQUIRE(same_bits(&ia.time, &ib.time, sizeof ia.time));
      REQUIRE(same_bits(&ia.root, &ib.root, sizeof ia.root));
      ++compared;
    }
  }
  CHECK(compared > kUsers * 500);
  CHECK(resets >= 2);  // user 1's exchange of the controllers and user 3's gap (each restarts the clock)
  int32_t rec = 0, swaps = 0, now = 0;
  REQUIRE(sb_pipeline_stream_events(user[1], &rec, &swaps, &now) == SB_OK);
  CHECK(swaps == 1);
  CHECK(now == 1);
  for (int u = 0; u < kUsers; ++u) {
    sb_calibration_report a{}, b{};
    a.struct_size = b.struct_size = sizeof a;
    REQUIRE(sb_pipeline_calibration(single[u], &a) == SB_OK);
    REQUIRE(sb_pipeline_calibration(user[u], &b) == SB_OK);
    CHECK(b.state == SB_CALIBRATION_CALIBRATED);
    CHECK(a.stature == b.stature);
    sb_pipeline_destroy(single[u]);
  }

  // Again from a reset of every user, counting allocations (push, read, calibration report).
  for (int u = 0; u < kUsers; ++u) REQUIRE(sb_pipeline_reset(user[u]) == SB_OK);
  sb_calibration_report r{};
  r.struct_size = sizeof r;
  long ok = 0;
  {
    sparsebody_test::AllocationCounter c;
    for (std::size_t t = 0; t < in[0].size(); ++t) {
      for (int u = 0; u < kUsers; ++u) frames[u] = in[u][t];
      sb_crowd_push(crowd, frames, kUsers, nullptr);
      for (int u = 0; u < kUsers; ++u) {
        ok += sb_pipeline_read(user[u], &ib, rb.data(), pb.data(), n) == SB_OK;
        sb_pipeline_calibration(user[u], &r);
      }
    }
    CHECK(c.count() == 0);
  }
  CHECK(ok > kUsers * 500);
  CHECK(sb_crowd_destroy(crowd) == SB_OK);
  sb_weights_destroy(stored);
}

}  // namespace

TEST_CASE("a crowd's users equal pipelines of their own through the C API, bit for bit, without allocating") {
  SUBCASE("LoBSTr") { check_crowd_equals_pipelines(SB_PIPELINE_LOBSTR); }
  SUBCASE("Neural3Points direct") { check_crowd_equals_pipelines(SB_PIPELINE_N3P_DIRECT); }
  SUBCASE("LoBSTr, int8 weights") { check_crowd_equals_pipelines(SB_PIPELINE_LOBSTR, SB_STORAGE_INT8); }
  SUBCASE("Neural3Points direct, f16 weights") { check_crowd_equals_pipelines(SB_PIPELINE_N3P_DIRECT, SB_STORAGE_F16); }
}

TEST_CASE("crowds: every bad argument") {
  sb_crowd* c = nullptr;
  sb_pipeline_config cfg = config(SB_PIPELINE_LOBSTR);
  auto says = [](const void* h, const char* what) { return std::strstr(sb_last_error(h), what) != nullptr; };
  CHECK(sb_crowd_create(weights(SB_PIPELINE_LOBSTR), &cfg, 3, nullptr) == SB_ERR_NULL);
  CHECK(sb_crowd_create(nullptr, &cfg, 3, &c) == SB_ERR_NULL);
  CHECK(c == nullptr);
  CHECK(sb_crowd_create(weights(SB_PIPELINE_LOBSTR), &cfg, 0, &c) == SB_ERR_INVALID_ARGUMENT);
  CHECK(says(nullptr, "0 users, expected 1-64"));
  CHECK(sb_crowd_create(weights(SB_PIPELINE_LOBSTR), &cfg, 65, &c) == SB_ERR_INVALID_ARGUMENT);
  CHECK(sb_crowd_create(weights(SB_PIPELINE_N3P_DIRECT), &cfg, 3, &c) == SB_ERR_MISMATCH);
  CHECK(says(nullptr, "sb_crowd_create: this pipeline needs LoBSTr weights"));
  cfg.window_mode = 1;
  CHECK(sb_crowd_create(weights(SB_PIPELINE_LOBSTR), &cfg, 3, &c) == SB_ERR_INVALID_ARGUMENT);
  CHECK(says(nullptr, "a crowd streams"));
  sb_pipeline_config phys = config(SB_PIPELINE_N3P_PHYSICS);
  CHECK(sb_crowd_create(weights(SB_PIPELINE_N3P_DIRECT), &phys, 3, &c) == SB_ERR_INVALID_ARGUMENT);
  CHECK(says(nullptr, "SB_PIPELINE_LOBSTR or SB_PIPELINE_N3P_DIRECT"));
  CHECK(c == nullptr);

  cfg.window_mode = 0;
  REQUIRE(sb_crowd_create(weights(SB_PIPELINE_LOBSTR), &cfg, 3, &c) == SB_OK);
  const auto in = user_frames();
  sb_tracker_frame f[3] = {in[0][0], in[0][0], in[0][0]};
  int32_t steps[3];
  CHECK(sb_crowd_push(c, nullptr, 3, steps) == SB_ERR_NULL);
  CHECK(sb_crowd_push(c, f, 2, steps) == SB_ERR_INVALID_ARGUMENT);
  CHECK(says(c, "2 frames for a crowd of 3 users"));
  f[2].time = std::numeric_limits<double>::quiet_NaN();
  CHECK(sb_crowd_push(c, f, 3, steps) == SB_ERR_INVALID_ARGUMENT);
  CHECK(says(c, "user 2: frame time is not finite"));
  f[2].time = 0;
  f[1].struct_size = 3;
  CHECK(sb_crowd_push(c, f, 3, steps) == SB_ERR_STRUCT_SIZE);
  CHECK(says(c, "user 1"));
  f[1].struct_size = sizeof(sb_tracker_frame);
  sb_pipeline* u = nullptr;
  REQUIRE(sb_crowd_user(c, 0, &u) == SB_OK);
  sb_pose_info info{};
  info.struct_size = sizeof info;
  CHECK(sb_pipeline_read(u, &info, nullptr, nullptr, 0) == SB_ERR_ORDER);  // the refused pushes pushed nothing
  f[1].pose[2].position.x = std::numeric_limits<float>::quiet_NaN();
  CHECK(sb_crowd_push(c, f, 3, steps) == SB_NONFINITE_POSE);
  CHECK(says(c, "user 1: tracker 2"));
  CHECK(sb_pipeline_read(u, &info, nullptr, nullptr, 0) == SB_OK);  // used, the tracker as lost
  CHECK(steps[0] == 1);
  CHECK(sb_crowd_user(c, 3, &u) == SB_ERR_INVALID_ARGUMENT);
  CHECK(u == nullptr);
  CHECK(sb_crowd_user(c, -1, &u) == SB_ERR_INVALID_ARGUMENT);
  CHECK(sb_crowd_user(c, 0, nullptr) == SB_ERR_NULL);
  CHECK(sb_crowd_size(c, nullptr) == SB_ERR_NULL);
  REQUIRE(sb_crowd_user(c, 2, &u) == SB_OK);
  CHECK(sb_pipeline_destroy(u) == SB_ERR_INVALID_ARGUMENT);
  CHECK(says(u, "sb_crowd_destroy frees it"));
  CHECK(sb_pipeline_push(u, &f[0], nullptr) == SB_OK);  // a user alone: allowed, as the crowd would step it
  // handles of the wrong type
  CHECK(sb_crowd_push(reinterpret_cast<sb_crowd*>(u), f, 3, steps) == SB_ERR_BAD_HANDLE);
  CHECK(sb_pipeline_push(reinterpret_cast<sb_pipeline*>(c), &f[0], nullptr) == SB_ERR_BAD_HANDLE);
  CHECK(sb_crowd_size(nullptr, &steps[0]) == SB_ERR_NULL);
  CHECK(sb_crowd_destroy(nullptr) == SB_OK);
  CHECK(sb_crowd_destroy(c) == SB_OK);
}
