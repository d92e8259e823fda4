// The C API (include/sparsebody/c/sparsebody.h) driven by arbitrary bytes, as a careless or hostile
// caller would: the bytes pick a pipeline and its config (struct_size and version sometimes wrong),
// then a sequence of calls - push (hostile poses, validity bits, time going backwards, NaN), read
// (NULL arrays, short capacities, wrong struct sizes), calibrate on a frame, set a joint
// calibration (NaN, 0, huge), recalibrate, reset, the skeleton queries with out-of-range indices,
// and calls on NULL or destroyed handles. Or (bit 7 of the config byte) a crowd of 0-5 users
// (sb_crowd_*): pushes of every user's frame at once (sometimes the wrong count), the other calls on
// a user's handle, and an attempt to destroy a user's handle. Checked: no crash or sanitizer report; every status is a
// known one with a message when it is an error; a read that says SB_OK copies finite numbers.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>

#include "fuzz_common.hpp"
#include "sparsebody/c/sparsebody_c_impl.hpp"

namespace {

using sparsebody_fuzz::Bytes;

float component(Bytes& b, float plausible) {
  const std::uint8_t k = b.u8();
  switch (k) {
    case 0: return std::numeric_limits<float>::quiet_NaN();
    case 1: return std::numeric_limits<float>::infinity();
    case 2: return -1e30f;
    case 3: return 0.0f;
    case 4: return plausible + 50.0f * (b.unit() - 0.5f);
    default: return plausible + 0.02f * ((k - 5) / 250.0f - 0.5f);
  }
}

void fail(const char* what, int s) {
  std::fprintf(stderr, "fuzz_capi: %s (status %d %s)\n", what, s, sb_status_name(static_cast<sb_status>(s)));
  std::abort();
}

// A status must be one the header lists; an error must leave a one-line message.
void check(sb_status s, const void* handle, const char* call) {
  if (s < SB_ERR_INTERNAL || s > SB_NONFINITE_POSE) fail(call, s);
  if (s == SB_ERR_INTERNAL) fail(call, s);  // an unexpected C++ exception reached the catch-all
  if (s < 0) {
    const char* m = sb_last_error(handle);
    if (!m) fail("error without a message", s);
    sparsebody_fuzz::check_message(m);  // one line, bounded
  }
}

sb_tracker_frame frame(Bytes& b, double& t, int k) {
  sb_tracker_frame f{};
  f.struct_size = (b.u8() == 0) ? 7u : sizeof(sb_tracker_frame);
  const std::uint8_t op = b.u8();
  switch (op & 7) {
    case 0: t -= 0.3 * b.unit(); break;
    case 1: t += 3.0; break;
    case 2: break;
    default: t += 1.0 / 72 * (0.5 + b.unit()); break;
  }
  f.time = op == 255 ? std::numeric_limits<double>::quiet_NaN() : t;
  f.valid = b.u8() & 15u;
  const double yaw = 0.3 * k / 72.0;
  const float base[4][3] = {{0, 1.62f, 0}, {-0.25f, 1.0f, -0.2f}, {0.25f, 1.0f, -0.2f}, {0, 0.95f, 0}};
  for (int j = 0; j < SB_TRACKER_COUNT; ++j) {
    f.pose[j].position = {component(b, base[j][0]), component(b, base[j][1]), component(b, base[j][2])};
    f.pose[j].orientation = {component(b, 0), component(b, float(std::sin(-yaw / 2))), component(b, 0),
                             component(b, float(std::cos(yaw / 2)))};
  }
  return f;
}

struct Weights {
  sb_weights* lobstr[3] = {};  // float, f16, int8 storage
  sb_weights* n3p[3] = {};
  sb_weights* questsim = nullptr;
  Weights() {
    bool ok = sb_weights_load(SB_MODEL_QUESTSIM, SPARSEBODY_SOURCE_DIR "/examples/weights/questsim_policy.json", &questsim) == SB_OK;
    for (int s = 0; s < 3; ++s)
      ok = ok &&
           sb_weights_load_storage(SB_MODEL_LOBSTR, SPARSEBODY_SOURCE_DIR "/examples/weights/lobstr_compact.weights.json", SB_STORAGE_FLOAT + s,
                                   &lobstr[s]) == SB_OK &&
           sb_weights_load_storage(SB_MODEL_N3P, SPARSEBODY_SOURCE_DIR "/examples/weights/n3p", SB_STORAGE_FLOAT + s, &n3p[s]) == SB_OK;
    if (!ok) {
      std::fprintf(stderr, "fuzz_capi: cannot load the shipped weights: %s\n", sb_last_error(nullptr));
      std::abort();
    }
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static Weights W;
  Bytes b{data, size};
  const std::uint8_t kb = b.u8();
  const int kind = 1 + kb % 4;       // LoBSTr, N3P direct, N3P physics, QuestSim
  const int storage = (kb >> 2) % 3;  // float, f16 or int8 weights (LoBSTr and Neural3Points)
  sb_pipeline_config cfg{};
  check(sb_pipeline_config_init(&cfg, kind), nullptr, "config_init");
  const std::uint8_t c = b.u8();
  if (c & 1) cfg.struct_size = 3;
  if (c & 2) cfg.version = 999;
  cfg.auto_calibration = (c >> 2) & 1;
  cfg.contact_ik = (c >> 3) & 1;
  cfg.window_mode = (c >> 4) & 1;
  if (c & 32) cfg.pipeline = 77;
  // the pipeline's own weights, or (bit 6) another model's
  const sb_weights* own = kind == 1 ? W.lobstr[storage] : kind == 4 ? W.questsim : W.n3p[storage];
  const sb_weights* other = kind == 1 ? W.n3p[storage] : W.lobstr[storage];
  const sb_weights* w = (c & 64) ? other : own;
  sb_pipeline* p = nullptr;
  sb_crowd* crowd = nullptr;
  int32_t users = 0;
  const sb_status created = (c & 128) ? sb_crowd_create(w, &cfg, users = b.u8() % 6, &crowd) : sb_pipeline_create(w, &cfg, &p);
  check(created, nullptr, "create");
  if (created != SB_OK) {
    if (p || crowd) fail("a failed create returned a handle", created);
    return 0;
  }
  if (crowd) check(sb_crowd_user(crowd, 0, &p), crowd, "crowd_user");
  static sb_quatf rot[256];
  static sb_vec3f pos[256];
  int32_t joints = 0;
  check(sb_pipeline_joint_count(p, &joints), p, "joint_count");
  double t = 0;
  for (int k = 0; b.more() && k < 120; ++k) {
    const std::uint8_t op = b.u8();
    sb_status s = SB_OK;
    if (crowd && (op & 16)) {  // the next calls on another user
      check(sb_crowd_user(crowd, static_cast<int32_t>(b.u8() % 8) - 1, &p), crowd, "crowd_user");
      if (!p) check(sb_crowd_user(crowd, 0, &p), crowd, "crowd_user");
    }
    if (op < 160 && crowd && (op & 2)) {
      static sb_tracker_frame f[8];
      static int32_t steps[8];
      for (int u = 0; u < users; ++u) f[u] = frame(b, t, k);
      const int32_t count = (op & 4) ? users + 1 : users;
      check(sb_crowd_push(crowd, f, count, (op & 1) ? nullptr : steps), crowd, "crowd_push");
    } else if (op < 160) {
      const sb_tracker_frame f = frame(b, t, k);
      int32_t steps = -1;
      s = sb_pipeline_push(p, &f, (op & 1) ? nullptr : &steps);
      check(s, p, "push");
    } else if (op < 200) {
      sb_pose_info info{};
      info.struct_size = (op & 1) ? sizeof(sb_pose_info) : 5u;
      const int32_t cap = (op & 2) ? joints : joints - 1;
      s = sb_pipeline_read(p, &info, (op & 4) ? rot : nullptr, (op & 8) ? pos : nullptr, cap);
      check(s, p, "read");
      if (s == SB_OK) {
        const int n = joints < 256 ? joints : 256;
        for (int j = 0; j < n && (op & 8); ++j)
          if (!std::isfinite(pos[j].x) || !std::isfinite(pos[j].y) || !std::isfinite(pos[j].z)) fail("non-finite position read", s);
        for (int j = 0; j < n && (op & 4); ++j)
          if (!std::isfinite(rot[j].x) || !std::isfinite(rot[j].w)) fail("non-finite rotation read", s);
        if (!std::isfinite(info.root.position.x) || !std::isfinite(info.user_scale)) fail("non-finite pose info", s);
      }
    } else if (op < 210) {
      const sb_tracker_frame f = frame(b, t, k);
      check(sb_pipeline_calibrate_frame(p, &f), p, "calibrate_frame");
    } else if (op < 220) {
      const double scales[] = {1.0, 0.0, -1.0, 1e9, std::numeric_limits<double>::quiet_NaN(), 0.8, 1.3, 10.0};
      check(sb_pipeline_set_joint_calibration(p, scales[b.u8() % 8]), p, "set_joint_calibration");
    } else if (op < 228) {
      check(sb_pipeline_recalibrate(p), p, "recalibrate");
    } else if (op < 234) {
      check(sb_pipeline_reset(p), p, "reset");
    } else if (op < 242) {
      sb_calibration_report r{};
      r.struct_size = (op & 1) ? sizeof(sb_calibration_report) : 9u;
      s = sb_pipeline_calibration(p, &r);
      check(s, p, "calibration");
      if (s == SB_OK && !std::memchr(r.message, 0, sizeof r.message)) fail("report message not terminated", s);
    } else if (op < 250) {
      const char* name = nullptr;
      const int32_t j = static_cast<int32_t>(b.u8()) - 10;
      s = sb_pipeline_joint_name(p, j, &name);
      check(s, p, "joint_name");
      if (s == SB_OK && (!name || std::strlen(name) == 0)) fail("empty joint name", s);
      static int32_t parents[256];
      check(sb_pipeline_joint_parents(p, parents, static_cast<int32_t>(b.u8())), p, "joint_parents");
      double fps = 0;
      check(sb_pipeline_frame_rate(p, &fps), p, "frame_rate");
      int32_t ev[3];
      check(sb_pipeline_stream_events(p, ev, ev + 1, ev + 2), p, "stream_events");
    } else {
      // NULL arguments and a NULL handle: errors, never a crash
      check(sb_pipeline_push(p, nullptr, nullptr), p, "push(NULL)");
      check(sb_pipeline_read(p, nullptr, rot, pos, joints), p, "read(NULL)");
      check(sb_pipeline_push(nullptr, nullptr, nullptr), nullptr, "push on NULL");
    }
  }
  if (crowd) {
    if (sb_pipeline_destroy(p) != SB_ERR_INVALID_ARGUMENT) fail("a crowd's user destroyed alone", SB_OK);
    check(sb_crowd_destroy(crowd), nullptr, "crowd_destroy");
  } else {
    check(sb_pipeline_destroy(p), nullptr, "destroy");
  }
  return 0;
}
