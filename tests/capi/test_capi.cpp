// The C API (sparsebody/c/sparsebody.h), compiled into this executable (capi_impl.cpp): every entry
// point's bad input (NULL, foreign or destroyed handles, wrong struct sizes, NaN, calls out of
// order) gives its error code and a message; the output equals the C++ pipelines' bit for bit on
// the same frames; push and read allocate nothing.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "capi_session.hpp"
#include "sparsebody/avatar/lobstr_pipeline.hpp"
#include "sparsebody/avatar/n3p_direct.hpp"
#include "sparsebody/avatar/n3p_physics.hpp"
#include "sparsebody/avatar/questsim_session.hpp"
#include "sparsebody/c/sparsebody.h"
#include "sparsebody/nn/storage.hpp"
#include "support/alloc_counter.hpp"

using namespace sparsebody;

namespace {

const std::string kWeights = SPARSEBODY_WEIGHTS_DIR;
const float kNaN = std::numeric_limits<float>::quiet_NaN();

const std::vector<trackers::TrackerFrame>& session() {
  static const auto s = capi_test::device_session(SPARSEBODY_TEST_CLIP);
  return s;
}

sb_weights* load(int model) {
  sb_weights* w = nullptr;
  const std::string path = model == SB_MODEL_LOBSTR     ? kWeights + "/lobstr_compact.weights.json"
                           : model == SB_MODEL_QUESTSIM ? kWeights + "/questsim_policy.json"
                                                        : kWeights + "/n3p";
  REQUIRE(sb_weights_load(model, path.c_str(), &w) == SB_OK);
  REQUIRE(w);
  return w;
}
sb_weights* lobstr_weights() {
  static sb_weights* w = load(SB_MODEL_LOBSTR);  // shared by the tests, freed at exit by the OS
  return w;
}
sb_weights* n3p_weights() {
  static sb_weights* w = load(SB_MODEL_N3P);
  return w;
}
sb_weights* questsim_weights() {
  static sb_weights* w = load(SB_MODEL_QUESTSIM);
  return w;
}

sb_pipeline* create(int kind) {
  sb_pipeline_config c;
  REQUIRE(sb_pipeline_config_init(&c, kind) == SB_OK);
  sb_pipeline* p = nullptr;
  sb_weights* w = kind == SB_PIPELINE_LOBSTR ? lobstr_weights() : kind == SB_PIPELINE_QUESTSIM ? questsim_weights() : n3p_weights();
  REQUIRE(sb_pipeline_create(w, &c, &p) == SB_OK);
  REQUIRE(p);
  return p;
}

sb_tracker_frame standing_frame(double t = 0) {
  sb_tracker_frame f = capi_test::to_c(session()[0]);
  f.time = t;
  return f;
}

bool mentions(const void* h, const char* what) { return std::strstr(sb_last_error(h), what) != nullptr; }

// Bits of a float (equality that also says NaN == NaN: a bit-for-bit comparison).
bool same(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

}  // namespace

TEST_CASE("weights loading: bad arguments, missing and malformed files, QuestSim, other sizes") {
  sb_weights* w = reinterpret_cast<sb_weights*>(0x1);
  CHECK(sb_weights_load(SB_MODEL_LOBSTR, "x", nullptr) == SB_ERR_NULL);
  CHECK(sb_weights_load(SB_MODEL_LOBSTR, nullptr, &w) == SB_ERR_NULL);
  CHECK(w == nullptr);  // *out cleared on failure
  CHECK(sb_weights_load(42, "x", &w) == SB_ERR_INVALID_ARGUMENT);
  CHECK(mentions(nullptr, "unknown model 42"));
  CHECK(sb_weights_load(SB_MODEL_QUESTSIM, "/nonexistent/questsim.json", &w) == SB_ERR_LOAD);
  CHECK(mentions(nullptr, "/nonexistent/questsim.json"));
  const std::string lobstr_file = kWeights + "/lobstr_compact.weights.json";
  CHECK(sb_weights_load(SB_MODEL_QUESTSIM, lobstr_file.c_str(), &w) == SB_ERR_LOAD);  // another kind of network
  CHECK(mentions(nullptr, "lobstr_compact.weights.json"));
  CHECK(w == nullptr);
  CHECK(sb_weights_load(SB_MODEL_LOBSTR, "/nonexistent/lobstr.json", &w) == SB_ERR_LOAD);
  CHECK(mentions(nullptr, "/nonexistent/lobstr.json"));
  CHECK(w == nullptr);
  const std::string garbage = std::string(SPARSEBODY_BINARY_DIR) + "/capi_garbage.json";
  std::ofstream(garbage) << "{\"format\": 3, \"tensors\": [1, 2";
  CHECK(sb_weights_load(SB_MODEL_LOBSTR, garbage.c_str(), &w) == SB_ERR_LOAD);
  CHECK(sb_weights_load(SB_MODEL_N3P, garbage.c_str(), &w) == SB_ERR_LOAD);
  // a LoBSTr file of another size than this build's (the H=32 test weights)
  const std::string small = std::string(SPARSEBODY_SOURCE_DIR) + "/tests/pipeline/golden/lobstr_pipeline_small.weights.json";
  CHECK(sb_weights_load(SB_MODEL_LOBSTR, small.c_str(), &w) == SB_ERR_UNSUPPORTED);
  CHECK(mentions(nullptr, "H=32"));
  // N3P: a prefix, a directory and one of the three files all work; a LoBSTr file as N3P does not
  for (const std::string& p : {kWeights + "/n3p", kWeights, kWeights + "/n3p_lower.json"}) {
    INFO(p);
    REQUIRE(sb_weights_load(SB_MODEL_N3P, p.c_str(), &w) == SB_OK);
    int32_t model = 0;
    CHECK(sb_weights_model(w, &model) == SB_OK);
    CHECK(model == SB_MODEL_N3P);
    CHECK(sb_weights_destroy(w) == SB_OK);
  }
  CHECK(sb_weights_load(SB_MODEL_N3P, (kWeights + "/lobstr_compact.weights.json").c_str(), &w) == SB_ERR_LOAD);
}

TEST_CASE("sb_weights_load_n3p: three explicit paths; NULL, missing or swapped files") {
  const std::string u = kWeights + "/n3p_upper.json", l = kWeights + "/n3p_lower.json", s = kWeights + "/n3p_signal.json";
  sb_weights* w = nullptr;
  CHECK(sb_weights_load_n3p(u.c_str(), l.c_str(), s.c_str(), nullptr) == SB_ERR_NULL);
  CHECK(sb_weights_load_n3p(nullptr, l.c_str(), s.c_str(), &w) == SB_ERR_NULL);
  CHECK(sb_weights_load_n3p(u.c_str(), "/nonexistent_lower.json", s.c_str(), &w) == SB_ERR_LOAD);
  CHECK(mentions(nullptr, "nonexistent_lower.json"));
  CHECK(sb_weights_load_n3p(l.c_str(), u.c_str(), s.c_str(), &w) == SB_ERR_LOAD);  // upper and lower swapped
  CHECK(w == nullptr);
  REQUIRE(sb_weights_load_n3p(u.c_str(), l.c_str(), s.c_str(), &w) == SB_OK);
  CHECK(sb_weights_destroy(w) == SB_OK);
}

TEST_CASE("weights handles: NULL, foreign, destroyed") {
  int32_t model = 0;
  CHECK(sb_weights_model(nullptr, &model) == SB_ERR_NULL);
  CHECK(sb_weights_model(lobstr_weights(), nullptr) == SB_ERR_NULL);
  double not_a_handle[64] = {};
  CHECK(sb_weights_model(reinterpret_cast<sb_weights*>(not_a_handle), &model) == SB_ERR_BAD_HANDLE);
  sb_pipeline* p = create(SB_PIPELINE_LOBSTR);
  CHECK(sb_weights_model(reinterpret_cast<sb_weights*>(p), &model) == SB_ERR_BAD_HANDLE);  // a pipeline is not weights
  CHECK(sb_weights_destroy(reinterpret_cast<sb_weights*>(p)) == SB_ERR_BAD_HANDLE);
  CHECK(sb_weights_destroy(nullptr) == SB_OK);
  sb_weights* w = load(SB_MODEL_LOBSTR);
  CHECK(sb_weights_destroy(w) == SB_OK);
  CHECK(sb_weights_destroy(w) == SB_ERR_BAD_HANDLE);  // twice (the tag was cleared)
  CHECK(sb_weights_model(w, &model) == SB_ERR_BAD_HANDLE);
  // the pipeline keeps its weights alive
  sb_weights* w2 = load(SB_MODEL_LOBSTR);
  sb_pipeline_config c;
  sb_pipeline_config_init(&c, SB_PIPELINE_LOBSTR);
  sb_pipeline* q = nullptr;
  REQUIRE(sb_pipeline_create(w2, &c, &q) == SB_OK);
  CHECK(sb_weights_destroy(w2) == SB_OK);
  const sb_tracker_frame f = standing_frame();
  CHECK(sb_pipeline_push(q, &f, nullptr) == SB_OK);
  sb_pose_info info{};
  info.struct_size = sizeof info;
  CHECK(sb_pipeline_read(q, &info, nullptr, nullptr, 0) == SB_OK);
  CHECK(sb_pipeline_destroy(q) == SB_OK);
  CHECK(sb_pipeline_destroy(p) == SB_OK);
}

TEST_CASE("sb_pipeline_config_init and sb_pipeline_create: every bad argument") {
  sb_pipeline_config c;
  CHECK(sb_pipeline_config_init(nullptr, SB_PIPELINE_LOBSTR) == SB_ERR_NULL);
  CHECK(sb_pipeline_config_init(&c, 0) == SB_ERR_INVALID_ARGUMENT);
  CHECK(sb_pipeline_config_init(&c, 99) == SB_ERR_INVALID_ARGUMENT);
  REQUIRE(sb_pipeline_config_init(&c, SB_PIPELINE_LOBSTR) == SB_OK);
  CHECK(c.struct_size == sizeof c);
  CHECK(c.version == SB_API_VERSION);
  CHECK(c.auto_calibration == 1);
  sb_pipeline* p = reinterpret_cast<sb_pipeline*>(0x1);
  CHECK(sb_pipeline_create(lobstr_weights(), &c, nullptr) == SB_ERR_NULL);
  CHECK(sb_pipeline_create(nullptr, &c, &p) == SB_ERR_NULL);
  CHECK(p == nullptr);
  CHECK(sb_pipeline_create(lobstr_weights(), nullptr, &p) == SB_ERR_NULL);
  double junk[64] = {};
  CHECK(sb_pipeline_create(reinterpret_cast<sb_weights*>(junk), &c, &p) == SB_ERR_BAD_HANDLE);
  auto bad = [&](auto edit, sb_status want, sb_weights* w) {
    sb_pipeline_config d = c;
    edit(d);
    sb_pipeline* q = nullptr;
    CHECK(sb_pipeline_create(w, &d, &q) == want);
    CHECK(q == nullptr);
  };
  bad([](sb_pipeline_config& d) { d.struct_size = 8; }, SB_ERR_STRUCT_SIZE, lobstr_weights());
  bad([](sb_pipeline_config& d) { d.struct_size = sizeof d + 4; }, SB_ERR_STRUCT_SIZE, lobstr_weights());
  bad([](sb_pipeline_config& d) { d.version = 2; }, SB_ERR_STRUCT_SIZE, lobstr_weights());
  bad([](sb_pipeline_config& d) { d.pipeline = SB_PIPELINE_QUESTSIM; }, SB_ERR_MISMATCH, lobstr_weights());
  CHECK(mentions(nullptr, "needs QuestSim weights, got LoBSTr"));
  bad([](sb_pipeline_config& d) { d.pipeline = SB_PIPELINE_N3P_DIRECT; }, SB_ERR_MISMATCH, questsim_weights());
  bad([](sb_pipeline_config& d) { d.pipeline = 7; }, SB_ERR_INVALID_ARGUMENT, lobstr_weights());
  bad([](sb_pipeline_config& d) { d.contact_ik = 2; }, SB_ERR_INVALID_ARGUMENT, lobstr_weights());
  bad([](sb_pipeline_config& d) { d.pipeline = SB_PIPELINE_N3P_DIRECT; }, SB_ERR_MISMATCH, lobstr_weights());
  bad([](sb_pipeline_config& d) { d.pipeline = SB_PIPELINE_LOBSTR; }, SB_ERR_MISMATCH, n3p_weights());
  bad([](sb_pipeline_config& d) { d.pipeline = SB_PIPELINE_N3P_PHYSICS, d.window_mode = 1; }, SB_ERR_INVALID_ARGUMENT, n3p_weights());
  CHECK(mentions(nullptr, "window_mode"));
}

TEST_CASE("pipeline handles: NULL, foreign, destroyed, a weights handle, in every pipeline call") {
  sb_pipeline* dead = create(SB_PIPELINE_N3P_DIRECT);
  REQUIRE(sb_pipeline_destroy(dead) == SB_OK);
  double junk[64] = {};
  sb_pipeline* handles[] = {nullptr, reinterpret_cast<sb_pipeline*>(junk), dead, reinterpret_cast<sb_pipeline*>(n3p_weights())};
  const sb_tracker_frame f = standing_frame();
  for (sb_pipeline* h : handles) {
    const sb_status want = h ? SB_ERR_BAD_HANDLE : SB_ERR_NULL;
    sb_pose_info info{};
    info.struct_size = sizeof info;
    int32_t n = 0, parents[64];
    const char* name = nullptr;
    double fps = 0;
    sb_calibration_report r{};
    r.struct_size = sizeof r;
    CHECK(sb_pipeline_push(h, &f, nullptr) == want);  // push after destroy
    CHECK(sb_pipeline_read(h, &info, nullptr, nullptr, 0) == want);
    CHECK(sb_pipeline_reset(h) == want);
    CHECK(sb_pipeline_joint_count(h, &n) == want);
    CHECK(sb_pipeline_joint_name(h, 0, &name) == want);
    CHECK(sb_pipeline_joint_parents(h, parents, 64) == want);
    CHECK(sb_pipeline_frame_rate(h, &fps) == want);
    CHECK(sb_pipeline_recalibrate(h) == want);
    CHECK(sb_pipeline_calibrate_frame(h, &f) == want);
    CHECK(sb_pipeline_set_joint_calibration(h, 1.0) == want);
    CHECK(sb_pipeline_calibration(h, &r) == want);
    int32_t ev[3];
    CHECK(sb_pipeline_stream_events(h, ev, ev + 1, ev + 2) == want);
    int64_t stand_ups = 0;
    CHECK(sb_pipeline_stand_ups(h, &stand_ups) == want);
    if (h) CHECK(sb_pipeline_destroy(h) == SB_ERR_BAD_HANDLE);
    if (h != handles[3]) CHECK(std::strlen(sb_last_error(h)) > 0);  // not a handle: this thread's message
  }
  CHECK(sb_pipeline_destroy(nullptr) == SB_OK);
}

TEST_CASE("push and read: NULL, struct sizes, NaN, bad flags, order of calls, capacity") {
  for (int kind : {SB_PIPELINE_LOBSTR, SB_PIPELINE_N3P_DIRECT, SB_PIPELINE_N3P_PHYSICS, SB_PIPELINE_QUESTSIM}) {
    INFO("pipeline " << kind);
    sb_pipeline* p = create(kind);
    int32_t n = 0;
    REQUIRE(sb_pipeline_joint_count(p, &n) == SB_OK);
    REQUIRE(n > 10);
    std::vector<sb_quatf> rot(static_cast<std::size_t>(n));
    std::vector<sb_vec3f> pos(static_cast<std::size_t>(n));
    sb_pose_info info{};
    info.struct_size = sizeof info;
    // read before any push
    CHECK(sb_pipeline_read(p, &info, rot.data(), pos.data(), n) == SB_ERR_ORDER);
    CHECK(mentions(p, "no frame pushed"));
    sb_tracker_frame f = standing_frame();
    CHECK(sb_pipeline_push(p, nullptr, nullptr) == SB_ERR_NULL);
    f.struct_size = 0;
    CHECK(sb_pipeline_push(p, &f, nullptr) == SB_ERR_STRUCT_SIZE);
    f = standing_frame();
    f.time = std::numeric_limits<double>::quiet_NaN();
    CHECK(sb_pipeline_push(p, &f, nullptr) == SB_ERR_INVALID_ARGUMENT);
    f.time = std::numeric_limits<double>::infinity();
    CHECK(sb_pipeline_push(p, &f, nullptr) == SB_ERR_INVALID_ARGUMENT);
    f = standing_frame();
    f.valid = 0x10;
    CHECK(sb_pipeline_push(p, &f, nullptr) == SB_ERR_INVALID_ARGUMENT);
    CHECK(sb_pipeline_read(p, &info, nullptr, nullptr, 0) == SB_ERR_ORDER);  // rejected pushes are no pushes
    // no valid headset yet: pushed, but no pose
    f = standing_frame();
    f.valid = 0;
    int32_t steps = -1;
    CHECK(sb_pipeline_push(p, &f, &steps) == SB_OK);
    CHECK(steps >= 0);
    CHECK(sb_pipeline_read(p, &info, rot.data(), pos.data(), n) == SB_NO_POSE);
    CHECK((info.flags & SB_POSE_OK) == 0);
    CHECK(info.joint_count == n);
    // a NaN headset flagged valid: used as lost, said
    f = standing_frame(1.0 / 30);
    f.pose[0].position.y = kNaN;
    CHECK(sb_pipeline_push(p, &f, nullptr) == SB_NONFINITE_POSE);
    CHECK(mentions(p, "head"));
    // good frames: a pose
    for (int i = 2; i < 8; ++i) {
      f = standing_frame(i / 30.0);
      CHECK(sb_pipeline_push(p, &f, &steps) == SB_OK);
    }
    CHECK(sb_pipeline_read(p, nullptr, rot.data(), pos.data(), n) == SB_ERR_NULL);
    info.struct_size = sizeof info - 8;
    CHECK(sb_pipeline_read(p, &info, rot.data(), pos.data(), n) == SB_ERR_STRUCT_SIZE);
    info.struct_size = sizeof info;
    CHECK(sb_pipeline_read(p, &info, rot.data(), pos.data(), n - 1) == SB_ERR_CAPACITY);
    CHECK(sb_pipeline_read(p, &info, nullptr, pos.data(), 0) == SB_ERR_CAPACITY);
    CHECK(sb_pipeline_read(p, &info, nullptr, nullptr, 0) == SB_OK);  // info only
    REQUIRE(sb_pipeline_read(p, &info, rot.data(), pos.data(), n) == SB_OK);
    CHECK((info.flags & SB_POSE_OK) != 0);
    CHECK((info.flags & SB_POSE_CALIBRATING) != 0);  // a third of a second: no standing window yet
    for (const auto& q : rot) CHECK(std::abs(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w - 1.0f) < 1e-4f);
    for (const auto& v : pos) CHECK((std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z)));
    // reset: reading before the next push is out of order again
    CHECK(sb_pipeline_reset(p) == SB_OK);
    CHECK(sb_pipeline_read(p, &info, nullptr, nullptr, 0) == SB_ERR_ORDER);
    // a tracking gap restarts the model: flagged
    f = standing_frame(0);
    sb_pipeline_push(p, &f, nullptr);
    f = standing_frame(10);
    sb_pipeline_push(p, &f, nullptr);
    sb_pipeline_read(p, &info, nullptr, nullptr, 0);
    CHECK((info.flags & SB_POSE_RESET) != 0);
    f = standing_frame(10 + 1.0 / 30);
    sb_pipeline_push(p, &f, nullptr);
    sb_pipeline_read(p, &info, nullptr, nullptr, 0);
    CHECK((info.flags & SB_POSE_RESET) == 0);
    CHECK(sb_pipeline_destroy(p) == SB_OK);
    CHECK(sb_pipeline_push(p, &f, nullptr) == SB_ERR_BAD_HANDLE);  // push after destroy
  }
}

TEST_CASE("skeleton queries: NULL, range, capacity") {
  sb_pipeline* p = create(SB_PIPELINE_N3P_DIRECT);
  int32_t n = 0;
  CHECK(sb_pipeline_joint_count(p, nullptr) == SB_ERR_NULL);
  REQUIRE(sb_pipeline_joint_count(p, &n) == SB_OK);
  const char* name = nullptr;
  CHECK(sb_pipeline_joint_name(p, 0, nullptr) == SB_ERR_NULL);
  CHECK(sb_pipeline_joint_name(p, -1, &name) == SB_ERR_INVALID_ARGUMENT);
  CHECK(sb_pipeline_joint_name(p, n, &name) == SB_ERR_INVALID_ARGUMENT);
  CHECK(name == nullptr);
  std::vector<int32_t> parents(static_cast<std::size_t>(n));
  CHECK(sb_pipeline_joint_parents(p, nullptr, n) == SB_ERR_NULL);
  CHECK(sb_pipeline_joint_parents(p, parents.data(), n - 1) == SB_ERR_CAPACITY);
  REQUIRE(sb_pipeline_joint_parents(p, parents.data(), n) == SB_OK);
  // the C++ pipeline's skeleton
  avatar::N3PDirect cpp(avatar::N3PDirect::load(kWeights + "/n3p"));
  REQUIRE(n == cpp.skeleton().size());
  for (int j = 0; j < n; ++j) {
    REQUIRE(sb_pipeline_joint_name(p, j, &name) == SB_OK);
    CHECK(std::string(name) == cpp.skeleton().names[static_cast<std::size_t>(j)]);
    CHECK(parents[static_cast<std::size_t>(j)] == cpp.skeleton().parents[static_cast<std::size_t>(j)]);
  }
  double fps = 0;
  CHECK(sb_pipeline_frame_rate(p, nullptr) == SB_ERR_NULL);
  CHECK(sb_pipeline_frame_rate(p, &fps) == SB_OK);
  CHECK(fps == cpp.meta().frame_rate);
  sb_pipeline_destroy(p);
}

// One frame with every tracker valid at these positions (head, left, right, pelvis), level orientations.
static sb_status push_positions(sb_pipeline* p, double time, const float (&pos)[4][3]) {
  sb_tracker_frame f{};
  f.struct_size = sizeof f;
  f.time = time;
  for (int k = 0; k < 4; ++k) {
    f.pose[k].position = {pos[k][0], pos[k][1], pos[k][2]};
    f.pose[k].orientation = {0, 0, 0, 1};
  }
  f.valid = SB_VALID_HEAD | SB_VALID_LEFT_HAND | SB_VALID_RIGHT_HAND | SB_VALID_PELVIS;
  int32_t steps = 0;
  return sb_pipeline_push(p, &f, &steps);
}

TEST_CASE("stream events: controllers held in the other hands are found and reported, reset forgets them") {
  // A user standing 3 s with the headset's "left" controller in the right hand (OpenXR: identity
  // headset faces -Z, +X is the user's right) and the other in the left, arms hanging.
  for (int kind : {SB_PIPELINE_LOBSTR, SB_PIPELINE_N3P_DIRECT, SB_PIPELINE_N3P_PHYSICS, SB_PIPELINE_QUESTSIM}) {
    INFO("pipeline " << kind);
    sb_pipeline* p = create(kind);
    REQUIRE(p);
    int32_t rec = -1, swaps = -1, now = -1;
    CHECK(sb_pipeline_stream_events(p, nullptr, &swaps, &now) == SB_ERR_NULL);
    REQUIRE(sb_pipeline_stream_events(p, &rec, &swaps, &now) == SB_OK);
    CHECK(rec == 0);
    CHECK(swaps == 0);
    CHECK(now == 0);
    for (int i = 0; i < 216; ++i) {
      const float sway = 0.003f * std::sin(0.1f * i);
      const float pos[4][3] = {{sway, 1.60f, 0}, {0.22f, 1.05f, -0.1f}, {-0.22f, 1.05f, -0.1f}, {0, 0.95f, 0}};
      REQUIRE(push_positions(p, i / 72.0, pos) == SB_OK);
    }
    REQUIRE(sb_pipeline_stream_events(p, &rec, &swaps, &now) == SB_OK);
    CHECK(rec == 0);
    CHECK(swaps == 1);
    CHECK(now == 1);
    REQUIRE(sb_pipeline_reset(p) == SB_OK);
    REQUIRE(sb_pipeline_stream_events(p, &rec, &swaps, &now) == SB_OK);
    CHECK(swaps == 1);  // counted since creation
    CHECK(now == 0);
    sb_pipeline_destroy(p);
  }
}

TEST_CASE("stand-ups: a user who stands up from a seat is counted (QuestSim: no detector); the grips reported") {
  // 3 s standing, 3 s seated (headset 0.45 m lower, controllers on the lap), a 1 s rise, 2 s standing.
  for (int kind : {SB_PIPELINE_LOBSTR, SB_PIPELINE_N3P_DIRECT, SB_PIPELINE_N3P_PHYSICS, SB_PIPELINE_QUESTSIM}) {
    INFO("pipeline " << kind);
    sb_pipeline* p = create(kind);
    REQUIRE(p);
    int64_t n = -1;
    CHECK(sb_pipeline_stand_ups(p, nullptr) == SB_ERR_NULL);
    REQUIRE(sb_pipeline_stand_ups(p, &n) == SB_OK);
    CHECK(n == 0);
    for (int i = 0; i < 9 * 72; ++i) {
      const double t = i / 72.0;
      const double down = t < 3 ? 0.0 : t < 6 ? 1.0 : t < 7 ? 0.5 + 0.5 * std::cos(3.14159265 * (t - 6)) : 0.0;  // 1: seated
      const float sway = 0.003f * std::sin(0.1f * i), d = float(down);
      const float pos[4][3] = {{sway, 1.60f - 0.45f * d, -0.05f * d},
                               {-0.22f + 0.07f * d, 1.05f - 0.4f * d, -0.1f - 0.2f * d},
                               {0.22f - 0.07f * d, 1.05f - 0.4f * d, -0.1f - 0.2f * d},
                               {0, 0.95f - 0.47f * d, 0}};
      REQUIRE(push_positions(p, t, pos) == SB_OK);
    }
    REQUIRE(sb_pipeline_stand_ups(p, &n) == SB_OK);
    CHECK(n == (kind == SB_PIPELINE_QUESTSIM ? 0 : 1));
    sb_calibration_report r{};
    r.struct_size = sizeof r;
    REQUIRE(sb_pipeline_calibration(p, &r) == SB_OK);
    for (int k = 0; k < 2; ++k) CHECK((r.grip_default[k] == 0 || r.grip_default[k] == 1));
    if (kind != SB_PIPELINE_QUESTSIM) {  // controllers held (as at a stand) in every window
      CHECK(r.grip_default[0] == 0);
      CHECK(r.grip_default[1] == 0);
      CHECK(r.grips_not_held == 0);
    }
    // the message names a controller still at the device model's grip exactly when the flags say so
    CHECK((r.grip_default[0] || r.grip_default[1]) == (std::strstr(r.message, "not seen held") != nullptr));
    sb_pipeline_destroy(p);
  }
}

TEST_CASE("calibration calls: bad frames and scales; explicit, joint and automatic calibration reported") {
  sb_pipeline* p = create(SB_PIPELINE_LOBSTR);
  sb_calibration_report r{};
  CHECK(sb_pipeline_calibration(p, nullptr) == SB_ERR_NULL);
  CHECK(sb_pipeline_calibration(p, &r) == SB_ERR_STRUCT_SIZE);  // struct_size 0
  r.struct_size = sizeof r;
  REQUIRE(sb_pipeline_calibration(p, &r) == SB_OK);
  CHECK(r.state == SB_CALIBRATION_DEFAULT);
  CHECK(std::strlen(r.message) > 0);
  sb_tracker_frame f = standing_frame();
  CHECK(sb_pipeline_calibrate_frame(p, nullptr) == SB_ERR_NULL);
  f.struct_size = 3;
  CHECK(sb_pipeline_calibrate_frame(p, &f) == SB_ERR_STRUCT_SIZE);
  f = standing_frame();
  f.valid &= ~SB_VALID_HEAD;
  CHECK(sb_pipeline_calibrate_frame(p, &f) == SB_ERR_INVALID_ARGUMENT);
  f = standing_frame();
  f.pose[0].orientation.w = kNaN;
  CHECK(sb_pipeline_calibrate_frame(p, &f) == SB_ERR_INVALID_ARGUMENT);
  f = standing_frame();
  f.pose[0].position.y = 0.2f;  // a headset 20 cm above the floor
  CHECK(sb_pipeline_calibrate_frame(p, &f) == SB_ERR_INVALID_ARGUMENT);
  sb_pipeline_calibration(p, &r);
  CHECK(r.state == SB_CALIBRATION_DEFAULT);  // unchanged
  f = standing_frame();
  CHECK(sb_pipeline_calibrate_frame(p, &f) == SB_OK);
  sb_pipeline_calibration(p, &r);
  CHECK(r.state == SB_CALIBRATION_CALIBRATED);
  CHECK(r.source == SB_CALIBRATION_SOURCE_EXPLICIT);
  CHECK(r.stature > 1.2);
  for (double s : {0.0, -1.0, 100.0, std::numeric_limits<double>::quiet_NaN()})
    CHECK(sb_pipeline_set_joint_calibration(p, s) == SB_ERR_INVALID_ARGUMENT);
  CHECK(sb_pipeline_set_joint_calibration(p, 0.9) == SB_OK);
  sb_pipeline_calibration(p, &r);
  CHECK(r.source == SB_CALIBRATION_SOURCE_APPLICATION);
  CHECK(r.scale == doctest::Approx(0.9));
  CHECK(sb_pipeline_recalibrate(p) == SB_OK);
  sb_pipeline_calibration(p, &r);
  CHECK(r.state == SB_CALIBRATION_DEFAULT);
  // the session's 2.5 s standing window: found automatically
  for (const auto& fr : session()) {
    const sb_tracker_frame c = capi_test::to_c(fr);
    sb_pipeline_push(p, &c, nullptr);
  }
  sb_pipeline_calibration(p, &r);
  CHECK(r.state == SB_CALIBRATION_CALIBRATED);
  CHECK(r.source == SB_CALIBRATION_SOURCE_AUTOMATIC);
  CHECK(r.frames_used >= 30);
  CHECK(r.confidence > 0);
  sb_pose_info info{};
  info.struct_size = sizeof info;
  sb_pipeline_read(p, &info, nullptr, nullptr, 0);
  CHECK((info.flags & SB_POSE_CALIBRATING) == 0);
  sb_pipeline_destroy(p);
  // auto_calibration = 0: the default body all session
  sb_pipeline_config c;
  sb_pipeline_config_init(&c, SB_PIPELINE_N3P_DIRECT);
  c.auto_calibration = 0;
  REQUIRE(sb_pipeline_create(n3p_weights(), &c, &p) == SB_OK);
  for (const auto& fr : session()) {
    const sb_tracker_frame cf = capi_test::to_c(fr);
    sb_pipeline_push(p, &cf, nullptr);
  }
  sb_pipeline_calibration(p, &r);
  CHECK(r.state == SB_CALIBRATION_DEFAULT);
  sb_pipeline_destroy(p);
}

TEST_CASE("messages: per handle, per thread; status names") {
  sb_pipeline* p = create(SB_PIPELINE_N3P_DIRECT);
  sb_pose_info info{};
  info.struct_size = 1;
  CHECK(sb_pipeline_read(p, &info, nullptr, nullptr, 0) == SB_ERR_STRUCT_SIZE);
  CHECK(mentions(p, "struct_size 1"));
  // another thread's failure changes neither this pipeline's message nor this thread's
  std::thread([] {
    sb_weights* w = nullptr;
    sb_weights_load(SB_MODEL_LOBSTR, "/other/thread.json", &w);
    CHECK(mentions(nullptr, "/other/thread.json"));
  }).join();
  CHECK(mentions(p, "struct_size 1"));
  CHECK(!mentions(nullptr, "/other/thread.json"));
  CHECK(std::string(sb_status_name(SB_ERR_CAPACITY)) == "SB_ERR_CAPACITY");
  CHECK(std::string(sb_status_name(static_cast<sb_status>(-99))) == "unknown");
  CHECK(sb_api_version() == SB_API_VERSION);
  sb_pipeline_destroy(p);
}

// The C API against the C++ pipelines on the same frames, bit for bit: every float of the pose,
// the contacts, the calibration.
template <class P>
void check_parity(P& cpp, int kind, int storage = SB_STORAGE_FLOAT) {
  sb_weights* stored = nullptr;  // weights of another storage than the shared float ones
  sb_pipeline* p = nullptr;
  if (storage == SB_STORAGE_FLOAT) {
    p = create(kind);
  } else {
    stored = capi_test::shipped_weights(kWeights, kind, storage);
    REQUIRE(stored);
    int32_t got = -1;
    REQUIRE(sb_weights_storage(stored, &got) == SB_OK);
    CHECK(got == storage);
    sb_pipeline_config c;
    REQUIRE(sb_pipeline_config_init(&c, kind) == SB_OK);
    REQUIRE(sb_pipeline_create(stored, &c, &p) == SB_OK);
  }
  const int n = cpp.skeleton().size();
  std::vector<sb_quatf> rot(static_cast<std::size_t>(n));
  std::vector<sb_vec3f> pos(static_cast<std::size_t>(n));
  sb_pose_info info{};
  info.struct_size = sizeof info;
  long mismatches = 0, poses = 0;
  for (const auto& fr : session()) {
    const int k = cpp.push(fr);
    const sb_tracker_frame c = capi_test::to_c(fr);
    int32_t steps = -1;
    const sb_status st = sb_pipeline_push(p, &c, &steps);
    REQUIRE(st >= 0);
    CHECK(steps == k);
    const sb_status rs = sb_pipeline_read(p, &info, rot.data(), pos.data(), n);
    REQUIRE(rs == (cpp.has_output() ? SB_OK : SB_NO_POSE));
    if (!cpp.has_output()) continue;
    ++poses;
    const double s = cpp.user_scale();
    int bad = 0;
    for (int j = 0; j < n; ++j) {
      const auto& q = cpp.pose().local[static_cast<std::size_t>(j)];
      const auto& w = cpp.world().position[static_cast<std::size_t>(j)];
      const sb_quatf& a = rot[static_cast<std::size_t>(j)];
      const sb_vec3f& b = pos[static_cast<std::size_t>(j)];
      bad += !same(a.x, float(q.x())) + !same(a.y, float(q.y())) + !same(a.z, float(q.z())) + !same(a.w, float(q.w()));
      bad += !same(b.x, float(w.x() * s)) + !same(b.y, float(w.y() * s)) + !same(b.z, float(w.z() * s));
    }
    const auto& r = cpp.pose().root_position;
    bad += !same(info.root.position.x, float(r.x() * s)) + !same(info.root.position.y, float(r.y() * s)) +
           !same(info.root.position.z, float(r.z() * s));
    bad += !same(info.user_scale, float(s));
    const auto& q0 = cpp.pose().local[0];
    bad += !same(info.root.orientation.x, float(q0.x())) + !same(info.root.orientation.w, float(q0.w()));
    bad += (info.contact[0] != int(cpp.contact(0))) + (info.contact[1] != int(cpp.contact(1)));
    bad += info.frames != cpp.frames();
    bad += ((info.flags & SB_POSE_CALIBRATING) != 0) != (cpp.calibration_report().status != features::CalibrationStatus::Calibrated);
    mismatches += bad != 0;
  }
  CHECK(poses > 200);
  CHECK(mismatches == 0);
  sb_calibration_report r{};
  r.struct_size = sizeof r;
  sb_pipeline_calibration(p, &r);
  CHECK(r.state == static_cast<int>(cpp.calibration_report().status));
  CHECK(r.state == SB_CALIBRATION_CALIBRATED);  // the session's standing window was found
  CHECK(r.stature == cpp.calibration_report().stature);
  CHECK(std::string(r.message) == cpp.calibration_report().message);
  sb_pipeline_destroy(p);
  sb_weights_destroy(stored);
}

TEST_CASE("the C API's output equals the C++ pipelines' bit for bit (same frames through both)") {
  SUBCASE("LoBSTr") {
    avatar::LoBSTrCompact cpp(avatar::LoBSTrCompact::load(kWeights + "/lobstr_compact.weights.json"));
    check_parity(cpp, SB_PIPELINE_LOBSTR);
  }
  SUBCASE("Neural3Points direct") {
    avatar::N3PDirect cpp(avatar::N3PDirect::load(kWeights + "/n3p"));
    check_parity(cpp, SB_PIPELINE_N3P_DIRECT);
  }
  SUBCASE("Neural3Points physics") {
    avatar::N3PPhysicsDefaultSizes<float> cpp(avatar::N3PDirect::load(kWeights + "/n3p"));
    check_parity(cpp, SB_PIPELINE_N3P_PHYSICS);
  }
  SUBCASE("QuestSim") {
    avatar::QuestSimSessionDefault cpp(avatar::QuestSimSessionDefault::load(kWeights + "/questsim_policy.json"));
    check_parity(cpp, SB_PIPELINE_QUESTSIM);
  }
  // Other weight storage (sb_weights_load_storage) against the C++ pipelines of that storage.
  SUBCASE("LoBSTr, int8 weights") {
    avatar::LoBSTrCompactQ8 cpp(avatar::LoBSTrCompactQ8::load(kWeights + "/lobstr_compact.weights.json"));
    check_parity(cpp, SB_PIPELINE_LOBSTR, SB_STORAGE_INT8);
  }
  SUBCASE("LoBSTr, f16 weights") {
    avatar::LoBSTrCompactF16 cpp(avatar::LoBSTrCompactF16::load(kWeights + "/lobstr_compact.weights.json"));
    check_parity(cpp, SB_PIPELINE_LOBSTR, SB_STORAGE_F16);
  }
  SUBCASE("Neural3Points direct, int8 weights") {
    avatar::N3PDirectQ8 cpp(avatar::N3PDirectQ8::load(kWeights + "/n3p"));
    check_parity(cpp, SB_PIPELINE_N3P_DIRECT, SB_STORAGE_INT8);
  }
  SUBCASE("Neural3Points physics, int8 weights") {
    avatar::N3PPhysicsQ8 cpp(avatar::N3PDirectQ8::load(kWeights + "/n3p"));
    check_parity(cpp, SB_PIPELINE_N3P_PHYSICS, SB_STORAGE_INT8);
  }
}

TEST_CASE("weight storage: auto follows the build's rule, QuestSim is float only, bad values refused") {
  sb_weights* w = nullptr;
  const std::string lobstr = kWeights + "/lobstr_compact.weights.json";
  REQUIRE(sb_weights_load_storage(SB_MODEL_LOBSTR, lobstr.c_str(), SB_STORAGE_AUTO, &w) == SB_OK);
  int32_t s = -1;
  REQUIRE(sb_weights_storage(w, &s) == SB_OK);
  CHECK(s == (nn::fastest_storage().storage == nn::Storage::q8 ? SB_STORAGE_INT8 : SB_STORAGE_FLOAT));
  CHECK(sb_weights_storage(w, nullptr) == SB_ERR_NULL);
  sb_weights_destroy(w);
  w = nullptr;
  REQUIRE(sb_weights_load(SB_MODEL_LOBSTR, lobstr.c_str(), &w) == SB_OK);
  REQUIRE(sb_weights_storage(w, &s) == SB_OK);
  CHECK(s == SB_STORAGE_FLOAT);  // sb_weights_load: float, as before
  sb_weights_destroy(w);
  w = nullptr;
  CHECK(sb_weights_load_storage(SB_MODEL_LOBSTR, lobstr.c_str(), 7, &w) == SB_ERR_INVALID_ARGUMENT);
  CHECK(mentions(nullptr, "unknown storage 7"));
  CHECK(w == nullptr);
  const std::string q = kWeights + "/questsim_policy.json";
  CHECK(sb_weights_load_storage(SB_MODEL_QUESTSIM, q.c_str(), SB_STORAGE_INT8, &w) == SB_ERR_UNSUPPORTED);
  CHECK(mentions(nullptr, "float only"));
  REQUIRE(sb_weights_load_storage(SB_MODEL_QUESTSIM, q.c_str(), SB_STORAGE_AUTO, &w) == SB_OK);
  REQUIRE(sb_weights_storage(w, &s) == SB_OK);
  CHECK(s == SB_STORAGE_FLOAT);
  sb_weights_destroy(w);
  CHECK(sb_weights_storage(nullptr, &s) == SB_ERR_NULL);
}

TEST_CASE("push and read allocate nothing (every pipeline, NaN frames, gaps, errors, calibration)") {
  for (int kind : {SB_PIPELINE_LOBSTR, SB_PIPELINE_N3P_DIRECT, SB_PIPELINE_N3P_PHYSICS, SB_PIPELINE_QUESTSIM}) {
    INFO("pipeline " << kind);
    sb_pipeline* p = create(kind);
    int32_t n = 0;
    sb_pipeline_joint_count(p, &n);
    std::vector<sb_quatf> rot(static_cast<std::size_t>(n));
    std::vector<sb_vec3f> pos(static_cast<std::size_t>(n));
    std::vector<sb_tracker_frame> frames;
    for (const auto& fr : session()) frames.push_back(capi_test::to_c(fr));
    frames[400].pose[1].position.x = kNaN;
    frames[500].time += 3.0;  // a gap (the clock jumps): the model restarts
    for (std::size_t i = 501; i < frames.size(); ++i) frames[i].time += 3.0;
    sb_pose_info info{};
    info.struct_size = sizeof info;
    sb_calibration_report r{};
    r.struct_size = sizeof r;
    for (std::size_t i = 0; i < 3; ++i) sb_pipeline_push(p, &frames[i], nullptr);
    long ok = 0;
    {
      sparsebody_test::AllocationCounter c;
      for (std::size_t i = 3; i < frames.size(); ++i) {
        sb_pipeline_push(p, &frames[i], nullptr);
        ok += sb_pipeline_read(p, &info, rot.data(), pos.data(), n) == SB_OK;
        sb_pipeline_calibration(p, &r);
      }
      sb_tracker_frame bad = frames[10];
      bad.time = std::numeric_limits<double>::quiet_NaN();
      sb_pipeline_push(p, &bad, nullptr);                          // an error message
      sb_pipeline_read(p, &info, rot.data(), pos.data(), 1);       // another
      sb_pipeline_push(nullptr, &bad, nullptr);                    // the thread's message
      sb_pipeline_recalibrate(p);
      sb_pipeline_push(p, &frames.back(), nullptr);
      CHECK(c.count() == 0);
    }
    CHECK(ok > 200);
    sb_pipeline_destroy(p);
  }
}

TEST_CASE("one weights handle, pipelines on two threads: each equals a single-threaded run") {
  auto run = [] {
    sb_pipeline* p = create(SB_PIPELINE_N3P_DIRECT);
    std::vector<sb_vec3f> pos(64);
    sb_pose_info info{};
    info.struct_size = sizeof info;
    std::vector<float> out;
    for (std::size_t i = 0; i < 400; ++i) {
      const sb_tracker_frame c = capi_test::to_c(session()[i]);
      sb_pipeline_push(p, &c, nullptr);
      if (sb_pipeline_read(p, &info, nullptr, pos.data(), 64) == SB_OK) out.push_back(pos[5].y);
    }
    sb_pipeline_destroy(p);
    return out;
  };
  n3p_weights();
  session();
  const std::vector<float> single = run();
  std::vector<float> a, b;
  std::thread ta([&] { a = run(); }), tb([&] { b = run(); });
  ta.join();
  tb.join();
  REQUIRE(single.size() > 100);
  CHECK(a == single);
  CHECK(b == single);
}

// Hostile input through every pipeline (what tests/fuzz does to the C++ pipelines): random NaN, Inf,
// huge values, non-unit quaternions, time going back and jumping, random validity bits, random
// struct sizes. Every call returns a defined status and every pose read is finite.
TEST_CASE("hostile frames: defined statuses, finite poses, no crash") {
  std::mt19937 rng(12345);
  std::uniform_real_distribution<float> u(-1, 1);
  const float specials[] = {kNaN, std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(), 1e30f, -1e30f, 0.0f};
  for (int kind : {SB_PIPELINE_LOBSTR, SB_PIPELINE_N3P_DIRECT, SB_PIPELINE_N3P_PHYSICS, SB_PIPELINE_QUESTSIM}) {
    INFO("pipeline " << kind);
    sb_pipeline* p = create(kind);
    int32_t n = 0;
    sb_pipeline_joint_count(p, &n);
    std::vector<sb_quatf> rot(static_cast<std::size_t>(n));
    std::vector<sb_vec3f> pos(static_cast<std::size_t>(n));
    sb_pose_info info{};
    info.struct_size = sizeof info;
    double t = 0;
    long poses = 0, nonfinite = 0, rejected = 0;
    for (int i = 0; i < 3000; ++i) {
      sb_tracker_frame f = capi_test::to_c(session()[static_cast<std::size_t>(i) % session().size()]);
      const int what = static_cast<int>(rng() % 10);
      t += what == 0 ? -0.5 : what == 1 ? 5.0 : 1.0 / 72;
      f.time = t;
      if (what == 2) f.valid = rng() % 16;
      float* v = &f.pose[rng() % 4].orientation.x;
      if (what == 3) v[rng() % 7] = specials[rng() % 6];
      if (what == 4) v[rng() % 7] = 10 * u(rng);
      if (what == 5) f.pose[0].position = {100 * u(rng), 100 * u(rng), 100 * u(rng)};
      if (what == 6 && rng() % 8 == 0) f.struct_size = rng() % 256;
      if (what == 7 && rng() % 8 == 0) f.time = specials[rng() % 3];
      const sb_status s = sb_pipeline_push(p, &f, nullptr);
      CHECK((s == SB_OK || s == SB_NONFINITE_POSE || s == SB_ERR_STRUCT_SIZE || s == SB_ERR_INVALID_ARGUMENT));
      nonfinite += s == SB_NONFINITE_POSE;
      rejected += s < 0;
      if (what == 8) sb_pipeline_calibrate_frame(p, &f);
      if (what == 9 && rng() % 50 == 0) sb_pipeline_recalibrate(p);
      const sb_status r = sb_pipeline_read(p, &info, rot.data(), pos.data(), n);
      REQUIRE((r == SB_OK || r == SB_NO_POSE || r == SB_ERR_ORDER));
      if (r != SB_OK) continue;
      ++poses;
      bool finite = std::isfinite(info.root.position.x) && std::isfinite(info.root.position.y) && std::isfinite(info.root.orientation.w);
      for (int j = 0; j < n; ++j)
        finite = finite && std::isfinite(pos[static_cast<std::size_t>(j)].x) && std::isfinite(pos[static_cast<std::size_t>(j)].y) &&
                 std::isfinite(pos[static_cast<std::size_t>(j)].z) && std::isfinite(rot[static_cast<std::size_t>(j)].w);
      REQUIRE(finite);
    }
    CHECK(poses > 1000);
    CHECK(nonfinite > 10);
    CHECK(rejected > 5);
    sb_pipeline_destroy(p);
  }
}
