// The C API (sparsebody/c/sparsebody.h) implemented once, in C++17. The shared library sparsebody_c
// is one TU including this; a user may compile it into one TU of their own instead (define
// SPARSEBODY_C_STATIC for that TU and for every C file including the header).
//
// Handles are small structs (a tag, the last error, a pointer to the pipeline) allocated apart
// from the pipeline, so a destroyed handle's memory stays small-bin heap: a stale pointer reads a
// cleared tag (not an unmapped page). Every entry point catches everything: no exception crosses.
// Per frame (push, read, queries): no allocation; messages go into fixed buffers (snprintf).
// A crowd (sb_crowd) is one avatar::LoBSTrBatch / N3PBatch; its users' handles are sb_pipelines whose
// impl views the batch's pipelines.
// Builds: LoBSTr compact (H 256, latent 128), Neural3Points direct and physics (the paper's sizes),
// each with float, f16 and int8 weights (Builds<W>, sb_weights_load_storage); QuestSim
// (avatar/questsim_session.hpp: the torque policy on a simulated avatar sized by the automatic
// calibration), float weights.
#pragma once
#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <memory>
#include <new>
#include <limits>
#include <string>
#include <system_error>
#include <type_traits>

#include "sparsebody/avatar/lobstr_batch.hpp"
#include "sparsebody/avatar/lobstr_pipeline.hpp"
#include "sparsebody/avatar/n3p_batch.hpp"
#include "sparsebody/avatar/n3p_direct.hpp"
#include "sparsebody/avatar/n3p_physics.hpp"
#include "sparsebody/avatar/questsim_session.hpp"
#include "sparsebody/c/sparsebody.h"
#include "sparsebody/core/error.hpp"
#include "sparsebody/io/weights_json.hpp"
#include "sparsebody/nn/storage.hpp"

namespace sparsebody::capi {

inline constexpr std::uint64_t kWeightsTag = 0x5342574549474854ull;   // "SBWEIGHT"
inline constexpr std::uint64_t kPipelineTag = 0x5342504950454c4eull;  // "SBPIPELN"
inline constexpr std::uint64_t kCrowdTag = 0x534243524f574453ull;     // "SBCROWDS"
inline constexpr std::uint64_t kDeadTag = 0x4445414444454144ull;      // written by destroy
inline constexpr std::size_t kMessage = 256;

using LoBSTr = avatar::LoBSTrCompact;
using N3PDirect = avatar::N3PDirect;
using N3PPhysics = avatar::N3PPhysicsDefaultSizes<float>;
using QuestSim = avatar::QuestSimSessionDefault;

// The LoBSTr and Neural3Points builds per weight storage W (float, nn::f16, nn::q8).
template <class W>
struct Builds {
  using LoBSTr = avatar::LoBSTrPipeline<float, 256, 128, W>;
  using N3PDirect = avatar::N3PPipeline<float, 64, 128, 128, W>;
  using N3PPhysics = avatar::N3PPhysicsDefaultSizes<W>;
};

template <class P>
inline constexpr bool kIsLoBSTr = std::is_same_v<P, Builds<float>::LoBSTr> || std::is_same_v<P, Builds<nn::f16>::LoBSTr> ||
                                  std::is_same_v<P, Builds<nn::q8>::LoBSTr>;
template <class P>
inline constexpr bool kIsN3PPhysics = std::is_same_v<P, Builds<float>::N3PPhysics> || std::is_same_v<P, Builds<nn::f16>::N3PPhysics> ||
                                      std::is_same_v<P, Builds<nn::q8>::N3PPhysics>;

template <class W>
struct StorageTag {
  using type = W;
};
// f(StorageTag<W>{}) for the weight type W of a resolved storage (SB_STORAGE_FLOAT / F16 / INT8).
template <class F>
decltype(auto) with_storage(std::int32_t storage, F&& f) {
  if (storage == SB_STORAGE_F16) return f(StorageTag<nn::f16>{});
  if (storage == SB_STORAGE_INT8) return f(StorageTag<nn::q8>{});
  return f(StorageTag<float>{});
}

inline char* thread_message() noexcept {
  static thread_local char m[kMessage] = "";
  return m;
}

inline void vformat(char* dst, const char* fmt, va_list ap) noexcept { std::vsnprintf(dst, kMessage, fmt, ap); }

// One abstract pipeline: the three builds behind one vtable (a virtual call per frame is noise).
struct PipelineBase {
  virtual ~PipelineBase() = default;
  // One push; flags gets SB_POSE_RESET / SB_POSE_FALLEN, time the shown pose's input time.
  virtual int push(const trackers::TrackerFrame& f, std::uint32_t& flags) noexcept = 0;
  // What push notes after each model step: the tick's time; true when the model restarted there.
  virtual bool on_tick(const trackers::TrackerFrame& tick, bool gap) noexcept = 0;
  virtual bool has_output() const noexcept = 0;
  virtual const pose::BodyPose& pose() const noexcept = 0;
  virtual const pose::WorldPose& world() const noexcept = 0;
  virtual const pose::Skeleton& skeleton() const noexcept = 0;
  virtual double user_scale() const noexcept = 0;
  virtual bool contact(int foot) const noexcept = 0;
  virtual long long frames() const noexcept = 0;
  virtual double shown_time() const noexcept = 0;
  virtual double frame_rate() const noexcept = 0;
  virtual const features::CalibrationReport& calibration_report() const noexcept = 0;
  virtual bool calibrate(const trackers::TrackerFrame& f) noexcept = 0;
  virtual void recalibrate() noexcept = 0;
  virtual void set_joint_calibration(double scale) noexcept = 0;
  virtual void reset() noexcept = 0;
  virtual int recentres() const noexcept = 0;
  virtual int controller_swaps() const noexcept = 0;
  virtual bool controllers_swapped() const noexcept = 0;
  virtual long long stand_ups() const noexcept = 0;
};

template <class P>
struct PipelineModel final : PipelineBase {
  std::unique_ptr<P> own_;  // the pipeline (sb_pipeline_create), or none: a crowd's user (CrowdModel owns it)
  P& p;
  double time_ = std::numeric_limits<double>::quiet_NaN();
  template <class W, class C>
  PipelineModel(const W& w, const C& c) : own_(std::make_unique<P>(w, c)), p(*own_) {}
  explicit PipelineModel(P& user) : p(user) {}

  static constexpr bool kQuestSim = std::is_same_v<P, QuestSim>;
  static constexpr bool kPhysics = kIsN3PPhysics<P> || kQuestSim;
  const trackers::SanitizedFrame& sanitized() const noexcept {
    if constexpr (kIsN3PPhysics<P>) return p.direct().tracker_stream().last_sanitized();
    else if constexpr (kQuestSim) return p.pipeline().tracker_stream().last_sanitized();
    else return p.tracker_stream().last_sanitized();
  }

  int push(const trackers::TrackerFrame& f, std::uint32_t& flags) noexcept override {
    bool reset = false;
    long long falls = 0, restarts = 0;
    if constexpr (kPhysics) falls = p.falls(), restarts = p.restarts();
    const int k = p.push(f, [&](const trackers::TrackerFrame& tick, bool gap) { reset = on_tick(tick, gap) || reset; });
    flags = 0;
    if constexpr (kPhysics) {
      if (p.restarts() != restarts) reset = true;
      if (p.falls() != falls) flags |= SB_POSE_FALLEN;
    }
    if (reset) flags |= SB_POSE_RESET;
    return k;
  }
  bool on_tick(const trackers::TrackerFrame& tick, bool gap) noexcept override {
    time_ = tick.time;
    return gap || sanitized().reset;
  }
  bool has_output() const noexcept override { return p.has_output(); }
  const pose::BodyPose& pose() const noexcept override { return p.pose(); }
  const pose::WorldPose& world() const noexcept override { return p.world(); }
  const pose::Skeleton& skeleton() const noexcept override { return p.skeleton(); }
  double user_scale() const noexcept override { return p.user_scale(); }
  bool contact(int foot) const noexcept override { return p.contact(foot); }
  long long frames() const noexcept override { return p.frames(); }
  double shown_time() const noexcept override {
    if constexpr (kPhysics) return p.output_time();
    else return time_;
  }
  double frame_rate() const noexcept override { return p.meta().frame_rate; }
  const features::CalibrationReport& calibration_report() const noexcept override { return p.calibration_report(); }
  bool calibrate(const trackers::TrackerFrame& f) noexcept override { return p.calibrate(f); }
  void recalibrate() noexcept override { p.recalibrate(); }
  void set_joint_calibration(double scale) noexcept override {
    // the demo's BVH path: identity offsets (trackers at the joints), only the size
    if constexpr (kQuestSim) {
      p.set_user_scale(scale);  // QuestSim: the avatar's size (a stature outside 1.0-2.4 m is ignored)
      p.pipeline().set_body_convention(true);  // trackers at the joints face +Z (the swap check's heading)
    } else if constexpr (kIsLoBSTr<P>) {
      features::Calibration c;
      c.scale = scale;
      p.set_calibration(c);
    } else {
      features::n3p::N3PCalibration c;
      c.base.scale = scale;
      p.set_calibration(c);
    }
  }
  void reset() noexcept override {
    p.reset();
    time_ = std::numeric_limits<double>::quiet_NaN();
  }
  int recentres() const noexcept override { return p.recentres(); }
  int controller_swaps() const noexcept override { return p.controller_swaps(); }
  bool controllers_swapped() const noexcept override { return p.controllers_swapped(); }
  long long stand_ups() const noexcept override {
    if constexpr (kQuestSim) return 0;  // no stand-up detector
    else return p.stand_ups();
  }
};

// A crowd (sb_crowd): one batch of users (avatar/lobstr_batch.hpp, n3p_batch.hpp).
struct CrowdBase {
  virtual ~CrowdBase() = default;
  virtual int size() const noexcept = 0;
  // A PipelineModel view of user i (its sb_pipeline handle's impl).
  virtual std::unique_ptr<PipelineBase> user_view(int i) = 0;
  // One frame per user; users[i] (user i's view) notes each of its ticks; steps[i] and flags[i]
  // (SB_POSE_RESET) get what its sb_pipeline_push would.
  virtual void push(const trackers::TrackerFrame* frames, PipelineBase* const* users, int* steps, std::uint32_t* flags) noexcept = 0;
};

template <class P, class Batch>
struct CrowdModel final : CrowdBase {
  Batch batch;
  template <class W, class C>
  CrowdModel(const W& w, int n, const C& c) : batch(w, n, c) {}
  int size() const noexcept override { return batch.size(); }
  std::unique_ptr<PipelineBase> user_view(int i) override { return std::make_unique<PipelineModel<P>>(batch[i]); }
  void push(const trackers::TrackerFrame* frames, PipelineBase* const* users, int* steps, std::uint32_t* flags) noexcept override {
    bool reset[nn::kBatchMax] = {};
    for (int i = 0; i < size(); ++i) steps[i] = 0;
    batch.push(frames, [&](int i, const trackers::TrackerFrame& tick, bool gap) {
      reset[i] = users[i]->on_tick(tick, gap) || reset[i];
      ++steps[i];
    });
    for (int i = 0; i < size(); ++i) flags[i] = reset[i] ? SB_POSE_RESET : 0u;
  }
};

}  // namespace sparsebody::capi

struct sb_weights {
  std::uint64_t tag = sparsebody::capi::kWeightsTag;
  std::int32_t model = 0;
  std::int32_t storage = SB_STORAGE_FLOAT;  // resolved: FLOAT, F16 or INT8; the fields of that storage are set
  std::shared_ptr<const sparsebody::capi::LoBSTr::Weights> lobstr;
  std::shared_ptr<const sparsebody::capi::Builds<sparsebody::nn::f16>::LoBSTr::Weights> lobstr_f16;
  std::shared_ptr<const sparsebody::capi::Builds<sparsebody::nn::q8>::LoBSTr::Weights> lobstr_q8;
  sparsebody::capi::N3PDirect::Weights n3p;
  sparsebody::capi::Builds<sparsebody::nn::f16>::N3PDirect::Weights n3p_f16;
  sparsebody::capi::Builds<sparsebody::nn::q8>::N3PDirect::Weights n3p_q8;
  std::shared_ptr<const sparsebody::capi::QuestSim::Weights> questsim;
  char error[sparsebody::capi::kMessage] = "";
};

struct sb_pipeline {
  std::uint64_t tag = sparsebody::capi::kPipelineTag;
  std::int32_t kind = 0;
  bool pushed = false;  // a push since create/reset: reading before it is SB_ERR_ORDER
  std::uint32_t flags = 0;
  std::int32_t steps = 0;
  std::unique_ptr<sparsebody::capi::PipelineBase> impl;
  sb_crowd* crowd = nullptr;  // the crowd that owns this user's handle (sb_crowd_user), else NULL
  char error[sparsebody::capi::kMessage] = "";
};

struct sb_crowd {
  std::uint64_t tag = sparsebody::capi::kCrowdTag;
  std::int32_t kind = 0;
  int users = 0;
  std::unique_ptr<sparsebody::capi::CrowdBase> impl;
  std::unique_ptr<sb_pipeline[]> user;                     // the users' handles (impl: views of the batch's pipelines)
  std::unique_ptr<sparsebody::capi::PipelineBase*[]> view;  // user[i].impl.get()
  char error[sparsebody::capi::kMessage] = "";
};

namespace sparsebody::capi {

// The status with its message in the handle's buffer (when there is one) and this thread's.
inline sb_status fail(char* handle_msg, sb_status s, const char* fmt, ...) noexcept {
  va_list ap;
  va_start(ap, fmt);
  char* t = thread_message();
  vformat(t, fmt, ap);
  va_end(ap);
  if (handle_msg && handle_msg != t) std::memcpy(handle_msg, t, kMessage);
  return s;
}

// Reading the tag of a pointer that is not a handle is the one unchecked step (documented).
template <class H>
bool live(const H* h, std::uint64_t tag) noexcept {
  return h && reinterpret_cast<std::uintptr_t>(h) % alignof(std::uint64_t) == 0 && *reinterpret_cast<const std::uint64_t*>(h) == tag;
}

#define SB_CHECK_PIPELINE(p)                                                                                \
  do {                                                                                                      \
    if (!(p)) return ::sparsebody::capi::fail(nullptr, SB_ERR_NULL, "%s: pipeline is NULL", __func__);     \
    if (!::sparsebody::capi::live(p, ::sparsebody::capi::kPipelineTag))                                     \
      return ::sparsebody::capi::fail(nullptr, SB_ERR_BAD_HANDLE, "%s: not a live sb_pipeline (foreign or destroyed)", __func__); \
  } while (0)

#define SB_CATCH_ALL(msg)                                                                                 \
  catch (const std::bad_alloc&) {                                                                         \
    return ::sparsebody::capi::fail(msg, SB_ERR_OUT_OF_MEMORY, "%s: out of memory", __func__);             \
  }                                                                                                       \
  catch (const ::sparsebody::LoadError& e) {                                                              \
    return ::sparsebody::capi::fail(msg, SB_ERR_LOAD, "%s", e.what());                                     \
  }                                                                                                       \
  catch (const std::exception& e) {                                                                       \
    return ::sparsebody::capi::fail(msg, SB_ERR_INTERNAL, "%s: %s", __func__, e.what());                   \
  }                                                                                                       \
  catch (...) {                                                                                           \
    return ::sparsebody::capi::fail(msg, SB_ERR_INTERNAL, "%s: unknown exception", __func__);              \
  }

inline bool finite_pose(const sb_posef& p) noexcept {
  const float v[7] = {p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w, p.position.x, p.position.y, p.position.z};
  for (float x : v)
    if (!std::isfinite(x)) return false;
  return true;
}

// The first tracker flagged valid whose pose has NaN/Inf, or -1.
inline int nonfinite_tracker(const sb_tracker_frame& f) noexcept {
  for (int k = 0; k < SB_TRACKER_COUNT; ++k)
    if (((f.valid >> k) & 1u) && !finite_pose(f.pose[k])) return k;
  return -1;
}

// The C frame as the pipelines' TrackerFrame (same numbers: the pipeline sees what C++ callers pass).
inline trackers::TrackerFrame to_frame(const sb_tracker_frame& f) noexcept {
  trackers::TrackerFrame t;
  t.time = f.time;
  for (int k = 0; k < trackers::kTrackerCount; ++k) {
    const sb_posef& p = f.pose[k];
    t.pose[k].orientation = {p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w};
    t.pose[k].position = {p.position.x, p.position.y, p.position.z};
    t.valid[k] = (f.valid >> k) & 1u;
  }
  return t;
}

// Checks shared by push and calibrate_frame; SB_OK or an error with the message set.
inline sb_status check_frame(char* msg, const char* fn, const sb_tracker_frame* f) noexcept {
  if (!f) return fail(msg, SB_ERR_NULL, "%s: frame is NULL", fn);
  if (f->struct_size != sizeof(sb_tracker_frame))
    return fail(msg, SB_ERR_STRUCT_SIZE, "%s: frame struct_size %u, expected %u", fn, f->struct_size, unsigned(sizeof(sb_tracker_frame)));
  if (!std::isfinite(f->time)) return fail(msg, SB_ERR_INVALID_ARGUMENT, "%s: frame time is not finite", fn);
  if (f->valid & ~0xFu) return fail(msg, SB_ERR_INVALID_ARGUMENT, "%s: valid has bits beyond SB_VALID_PELVIS (0x%x)", fn, f->valid);
  return SB_OK;
}

// Loads and checks N3P weights by building one pipeline (its constructor validates the skeleton).
// The weights of storage W in a handle.
template <class W, class H>
auto& lobstr_of(H& w) noexcept {
  if constexpr (std::is_same_v<W, nn::f16>) return w.lobstr_f16;
  else if constexpr (std::is_same_v<W, nn::q8>) return w.lobstr_q8;
  else return w.lobstr;
}
template <class W, class H>
auto& n3p_of(H& w) noexcept {
  if constexpr (std::is_same_v<W, nn::f16>) return w.n3p_f16;
  else if constexpr (std::is_same_v<W, nn::q8>) return w.n3p_q8;
  else return w.n3p;
}

template <class W>
inline void load_n3p(sb_weights& w, const std::string& sig, const std::string& lo, const std::string& up) {
  using Direct = typename Builds<W>::N3PDirect;
  using Pred = typename Direct::Predictor;
  auto& n = n3p_of<W>(w);
  n.sig = nn::NetworkWeights<typename Pred::SigNet>::load(sig, networks::kN3PSignalKind);
  n.lo = nn::NetworkWeights<typename Pred::LoNet>::load(lo, networks::kN3PLowerKind);
  n.up = nn::NetworkWeights<typename Pred::UpNet>::load(up, networks::kN3PUpperKind);
  Direct check(n);
  (void)check;
}

// The checks of sb_pipeline_create and sb_crowd_create (fn: the caller's name for the message).
inline sb_status check_create(const sb_weights* w, const sb_pipeline_config* cfg, const char* fn) noexcept {
  if (!w || !cfg) return fail(nullptr, SB_ERR_NULL, "%s: %s is NULL", fn, w ? "cfg" : "weights");
  if (!live(w, kWeightsTag)) return fail(nullptr, SB_ERR_BAD_HANDLE, "%s: not a live sb_weights (foreign or destroyed)", fn);
  if (cfg->struct_size != sizeof(sb_pipeline_config))
    return fail(nullptr, SB_ERR_STRUCT_SIZE, "%s: cfg struct_size %u, expected %u", fn, cfg->struct_size, unsigned(sizeof(sb_pipeline_config)));
  if (cfg->version != SB_API_VERSION)
    return fail(nullptr, SB_ERR_STRUCT_SIZE, "%s: cfg version %u, this library is %u", fn, cfg->version, SB_API_VERSION);
  const int kind = cfg->pipeline;
  if (kind < SB_PIPELINE_LOBSTR || kind > SB_PIPELINE_QUESTSIM) return fail(nullptr, SB_ERR_INVALID_ARGUMENT, "%s: unknown pipeline %d", fn, kind);
  for (int32_t v : {cfg->auto_calibration, cfg->contact_ik, cfg->window_mode})
    if (v != 0 && v != 1) return fail(nullptr, SB_ERR_INVALID_ARGUMENT, "%s: a flag of cfg is %d, not 0 or 1", fn, int(v));
  if (cfg->window_mode && kind != SB_PIPELINE_LOBSTR) return fail(nullptr, SB_ERR_INVALID_ARGUMENT, "%s: window_mode is LoBSTr-only", fn);
  const int need = kind == SB_PIPELINE_LOBSTR ? SB_MODEL_LOBSTR : kind == SB_PIPELINE_QUESTSIM ? SB_MODEL_QUESTSIM : SB_MODEL_N3P;
  auto model_name = [](int m) { return m == SB_MODEL_LOBSTR ? "LoBSTr" : m == SB_MODEL_QUESTSIM ? "QuestSim" : "Neural3Points"; };
  if (w->model != need)
    return fail(nullptr, SB_ERR_MISMATCH, "%s: this pipeline needs %s weights, got %s", fn, model_name(need), model_name(w->model));
  return SB_OK;
}

inline avatar::LoBSTrConfig lobstr_config(const sb_pipeline_config& cfg) noexcept {
  avatar::LoBSTrConfig pc;
  pc.mode = cfg.window_mode ? avatar::RunMode::Window : avatar::RunMode::Streaming;
  pc.contact_ik = cfg.contact_ik != 0;
  pc.calibration.enabled = cfg.auto_calibration != 0;
  return pc;
}

inline avatar::N3PConfig n3p_config(const sb_pipeline_config& cfg) noexcept {
  avatar::N3PConfig pc;
  pc.foot_ik = cfg.contact_ik != 0;
  pc.calibration.enabled = cfg.auto_calibration != 0;
  return pc;
}

}  // namespace sparsebody::capi

extern "C" {

SPARSEBODY_API uint32_t sb_api_version(void) { return SB_API_VERSION; }

SPARSEBODY_API const char* sb_status_name(sb_status s) {
  switch (s) {
    case SB_OK: return "SB_OK";
    case SB_NO_POSE: return "SB_NO_POSE";
    case SB_NONFINITE_POSE: return "SB_NONFINITE_POSE";
    case SB_ERR_NULL: return "SB_ERR_NULL";
    case SB_ERR_BAD_HANDLE: return "SB_ERR_BAD_HANDLE";
    case SB_ERR_STRUCT_SIZE: return "SB_ERR_STRUCT_SIZE";
    case SB_ERR_INVALID_ARGUMENT: return "SB_ERR_INVALID_ARGUMENT";
    case SB_ERR_CAPACITY: return "SB_ERR_CAPACITY";
    case SB_ERR_ORDER: return "SB_ERR_ORDER";
    case SB_ERR_LOAD: return "SB_ERR_LOAD";
    case SB_ERR_NO_TRAINED_WEIGHTS: return "SB_ERR_NO_TRAINED_WEIGHTS";
    case SB_ERR_UNSUPPORTED: return "SB_ERR_UNSUPPORTED";
    case SB_ERR_MISMATCH: return "SB_ERR_MISMATCH";
    case SB_ERR_OUT_OF_MEMORY: return "SB_ERR_OUT_OF_MEMORY";
    case SB_ERR_INTERNAL: return "SB_ERR_INTERNAL";
  }
  return "unknown";
}

SPARSEBODY_API const char* sb_last_error(const void* handle) {
  namespace c = sparsebody::capi;
  if (c::live(static_cast<const sb_pipeline*>(handle), c::kPipelineTag)) return static_cast<const sb_pipeline*>(handle)->error;
  if (c::live(static_cast<const sb_weights*>(handle), c::kWeightsTag)) return static_cast<const sb_weights*>(handle)->error;
  if (c::live(static_cast<const sb_crowd*>(handle), c::kCrowdTag)) return static_cast<const sb_crowd*>(handle)->error;
  return c::thread_message();
}

SPARSEBODY_API sb_status sb_weights_load(int32_t model, const char* path, sb_weights** out) {
  return sb_weights_load_storage(model, path, SB_STORAGE_FLOAT, out);
}

SPARSEBODY_API sb_status sb_weights_load_storage(int32_t model, const char* path, int32_t storage, sb_weights** out) {
  namespace c = sparsebody::capi;
  namespace nn = sparsebody::nn;
  if (!out) return c::fail(nullptr, SB_ERR_NULL, "sb_weights_load: out is NULL");
  *out = nullptr;
  if (!path) return c::fail(nullptr, SB_ERR_NULL, "sb_weights_load: path is NULL");
  try {
    if (model != SB_MODEL_LOBSTR && model != SB_MODEL_N3P && model != SB_MODEL_QUESTSIM)
      return c::fail(nullptr, SB_ERR_INVALID_ARGUMENT, "sb_weights_load: unknown model %d", int(model));
    if (storage < SB_STORAGE_AUTO || storage > SB_STORAGE_INT8)
      return c::fail(nullptr, SB_ERR_INVALID_ARGUMENT, "sb_weights_load: unknown storage %d", int(storage));
    if (storage == SB_STORAGE_AUTO)  // the build's rule (nn/storage.hpp), without the f16 size test
      storage = model == SB_MODEL_QUESTSIM || nn::fastest_storage().storage != nn::Storage::q8 ? SB_STORAGE_FLOAT : SB_STORAGE_INT8;
    if (model == SB_MODEL_QUESTSIM && storage != SB_STORAGE_FLOAT)
      return c::fail(nullptr, SB_ERR_UNSUPPORTED, "sb_weights_load: QuestSim weights are float only in this library (storage %d)", int(storage));
    auto w = std::make_unique<sb_weights>();
    w->model = model;
    w->storage = storage;
    if (model == SB_MODEL_LOBSTR) {
      // the sizes from the file's meta first, as the demo does: a clear message for other builds
      const sparsebody::io::WeightsDocument doc = sparsebody::io::read_weights_file(path);
      const auto& meta = doc.info.meta;
      auto size_of = [&](const char* key, int def) {
        return meta.contains(key) && meta[key].is_number_integer() ? meta[key].get<int>() : def;
      };
      const int hidden = size_of("hidden", 256), latent = size_of("latent", 128);
      if (hidden != c::LoBSTr::kHidden || latent != c::LoBSTr::kLatent)
        return c::fail(nullptr, SB_ERR_UNSUPPORTED, "%s: LoBSTr H=%d latent=%d; this build has H=%d latent=%d only", path, hidden, latent,
                       c::LoBSTr::kHidden, c::LoBSTr::kLatent);
      c::with_storage(storage, [&](auto tag) {
        using W = typename decltype(tag)::type;
        c::lobstr_of<W>(*w) = c::Builds<W>::LoBSTr::load(path);
      });
    } else if (model == SB_MODEL_QUESTSIM) {
      w->questsim = c::QuestSim::load(path);  // kind "questsim_policy", the default avatar's sizes
    } else {
      const std::string p = sparsebody::predict::n3p_weights_prefix(path);
      c::with_storage(storage, [&](auto tag) {
        c::load_n3p<typename decltype(tag)::type>(*w, p + "_signal.json", p + "_lower.json", p + "_upper.json");
      });
    }
    *out = w.release();
    return SB_OK;
  }
  SB_CATCH_ALL(nullptr)
}

SPARSEBODY_API sb_status sb_weights_storage(const sb_weights* w, int32_t* storage) {
  namespace c = sparsebody::capi;
  if (!w) return c::fail(nullptr, SB_ERR_NULL, "sb_weights_storage: weights is NULL");
  if (!c::live(w, c::kWeightsTag)) return c::fail(nullptr, SB_ERR_BAD_HANDLE, "sb_weights_storage: not a live sb_weights");
  if (!storage) return c::fail(nullptr, SB_ERR_NULL, "sb_weights_storage: storage is NULL");
  *storage = w->storage;
  return SB_OK;
}

SPARSEBODY_API sb_status sb_weights_load_n3p(const char* upper, const char* lower, const char* signal, sb_weights** out) {
  namespace c = sparsebody::capi;
  if (!out) return c::fail(nullptr, SB_ERR_NULL, "sb_weights_load_n3p: out is NULL");
  *out = nullptr;
  if (!upper || !lower || !signal) return c::fail(nullptr, SB_ERR_NULL, "sb_weights_load_n3p: a path is NULL");
  try {
    auto w = std::make_unique<sb_weights>();
    w->model = SB_MODEL_N3P;
    c::load_n3p<float>(*w, signal, lower, upper);
    *out = w.release();
    return SB_OK;
  }
  SB_CATCH_ALL(nullptr)
}

SPARSEBODY_API sb_status sb_weights_model(const sb_weights* w, int32_t* model) {
  namespace c = sparsebody::capi;
  if (!w) return c::fail(nullptr, SB_ERR_NULL, "sb_weights_model: weights is NULL");
  if (!c::live(w, c::kWeightsTag)) return c::fail(nullptr, SB_ERR_BAD_HANDLE, "sb_weights_model: not a live sb_weights");
  if (!model) return c::fail(nullptr, SB_ERR_NULL, "sb_weights_model: model is NULL");
  *model = w->model;
  return SB_OK;
}

SPARSEBODY_API sb_status sb_weights_destroy(sb_weights* w) {
  namespace c = sparsebody::capi;
  if (!w) return SB_OK;
  if (!c::live(w, c::kWeightsTag)) return c::fail(nullptr, SB_ERR_BAD_HANDLE, "sb_weights_destroy: not a live sb_weights (foreign or destroyed)");
  try {
    w->tag = c::kDeadTag;
    delete w;
    return SB_OK;
  }
  SB_CATCH_ALL(nullptr)
}

SPARSEBODY_API sb_status sb_pipeline_config_init(sb_pipeline_config* cfg, int32_t pipeline) {
  namespace c = sparsebody::capi;
  if (!cfg) return c::fail(nullptr, SB_ERR_NULL, "sb_pipeline_config_init: cfg is NULL");
  if (pipeline < SB_PIPELINE_LOBSTR || pipeline > SB_PIPELINE_QUESTSIM)
    return c::fail(nullptr, SB_ERR_INVALID_ARGUMENT, "sb_pipeline_config_init: unknown pipeline %d", int(pipeline));
  *cfg = sb_pipeline_config{};
  cfg->struct_size = sizeof(sb_pipeline_config);
  cfg->version = SB_API_VERSION;
  cfg->pipeline = pipeline;
  cfg->auto_calibration = 1;
  cfg->contact_ik = 1;
  cfg->window_mode = 0;
  return SB_OK;
}

SPARSEBODY_API sb_status sb_pipeline_create(const sb_weights* w, const sb_pipeline_config* cfg, sb_pipeline** out) {
  namespace c = sparsebody::capi;
  namespace a = sparsebody::avatar;
  if (!out) return c::fail(nullptr, SB_ERR_NULL, "sb_pipeline_create: out is NULL");
  *out = nullptr;
  if (const sb_status s = c::check_create(w, cfg, "sb_pipeline_create"); s != SB_OK) return s;
  const int kind = cfg->pipeline;
  try {
    auto h = std::make_unique<sb_pipeline>();
    h->kind = kind;
    if (kind == SB_PIPELINE_LOBSTR) {
      c::with_storage(w->storage, [&](auto tag) {
        using W = typename decltype(tag)::type;
        h->impl = std::make_unique<c::PipelineModel<typename c::Builds<W>::LoBSTr>>(c::lobstr_of<W>(*w), c::lobstr_config(*cfg));
      });
    } else if (kind == SB_PIPELINE_N3P_DIRECT) {
      c::with_storage(w->storage, [&](auto tag) {
        using W = typename decltype(tag)::type;
        h->impl = std::make_unique<c::PipelineModel<typename c::Builds<W>::N3PDirect>>(c::n3p_of<W>(*w), c::n3p_config(*cfg));
      });
    } else if (kind == SB_PIPELINE_QUESTSIM) {
      a::QuestSimSessionConfig pc;  // contact_ik does not apply (a simulated body)
      pc.calibration.enabled = cfg->auto_calibration != 0;
      h->impl = std::make_unique<c::PipelineModel<c::QuestSim>>(w->questsim, pc);
    } else {
      a::N3PPhysicsConfig pc;  // its direct pipeline's defaults differ from N3PConfig's: set the two flags only
      pc.direct.foot_ik = cfg->contact_ik != 0;
      pc.direct.calibration.enabled = cfg->auto_calibration != 0;
      c::with_storage(w->storage, [&](auto tag) {
        using W = typename decltype(tag)::type;
        h->impl = std::make_unique<c::PipelineModel<typename c::Builds<W>::N3PPhysics>>(c::n3p_of<W>(*w), pc);
      });
    }
    *out = h.release();
    return SB_OK;
  }
  SB_CATCH_ALL(nullptr)
}

SPARSEBODY_API sb_status sb_pipeline_destroy(sb_pipeline* p) {
  namespace c = sparsebody::capi;
  if (!p) return SB_OK;
  SB_CHECK_PIPELINE(p);
  if (p->crowd)
    return c::fail(p->error, SB_ERR_INVALID_ARGUMENT, "sb_pipeline_destroy: a crowd's user (sb_crowd_user): sb_crowd_destroy frees it");
  try {
    p->tag = c::kDeadTag;
    delete p;
    return SB_OK;
  }
  SB_CATCH_ALL(nullptr)
}

SPARSEBODY_API sb_status sb_pipeline_reset(sb_pipeline* p) {
  SB_CHECK_PIPELINE(p);
  try {
  p->impl->reset();
  p->pushed = false;
  p->flags = 0;
  p->steps = 0;
  return SB_OK;
  }
  SB_CATCH_ALL(p->error)
}

SPARSEBODY_API sb_status sb_pipeline_push(sb_pipeline* p, const sb_tracker_frame* frame, int32_t* steps) {
  namespace c = sparsebody::capi;
  SB_CHECK_PIPELINE(p);
  try {
  if (const sb_status s = c::check_frame(p->error, "sb_pipeline_push", frame); s != SB_OK) return s;
  const int bad = c::nonfinite_tracker(*frame);  // used as lost (the sanitizer's rule), said here
  const int k = p->impl->push(c::to_frame(*frame), p->flags);
  p->steps = k;
  p->pushed = true;
  if (steps) *steps = k;
  if (bad >= 0)
    return c::fail(p->error, SB_NONFINITE_POSE, "sb_pipeline_push: tracker %d (%s) is flagged valid but not finite: treated as lost", bad,
                   sparsebody::trackers::tracker_name(bad));
  return SB_OK;
  }
  SB_CATCH_ALL(p->error)
}

SPARSEBODY_API sb_status sb_pipeline_read(sb_pipeline* p, sb_pose_info* info, sb_quatf* local_rotations, sb_vec3f* world_positions,
                                          int32_t capacity) {
  namespace c = sparsebody::capi;
  SB_CHECK_PIPELINE(p);
  try {
  if (!info) return c::fail(p->error, SB_ERR_NULL, "sb_pipeline_read: info is NULL");
  if (info->struct_size != sizeof(sb_pose_info))
    return c::fail(p->error, SB_ERR_STRUCT_SIZE, "sb_pipeline_read: info struct_size %u, expected %u", info->struct_size,
                   unsigned(sizeof(sb_pose_info)));
  const c::PipelineBase& q = *p->impl;
  const int n = q.skeleton().size();
  if ((local_rotations || world_positions) && capacity < n)
    return c::fail(p->error, SB_ERR_CAPACITY, "sb_pipeline_read: capacity %d, the skeleton has %d joints", int(capacity), n);
  if (!p->pushed) return c::fail(p->error, SB_ERR_ORDER, "sb_pipeline_read: no frame pushed yet (since create or reset)");
  const double s = q.user_scale();
  std::uint32_t flags = p->flags;
  if (q.calibration_report().status != sparsebody::features::CalibrationStatus::Calibrated) flags |= SB_POSE_CALIBRATING;
  const bool ok = q.has_output();
  if (ok) flags |= SB_POSE_OK;
  const std::uint32_t size = info->struct_size;
  *info = sb_pose_info{};
  info->struct_size = size;
  info->flags = flags;
  info->time = q.shown_time();
  info->frames = q.frames();
  info->steps = p->steps;
  info->joint_count = n;
  info->user_scale = static_cast<float>(s);
  info->contact[0] = q.contact(0);
  info->contact[1] = q.contact(1);
  if (!ok) return c::fail(p->error, SB_NO_POSE, "sb_pipeline_read: no pose yet (no valid headset frame so far)");
  const auto& pose = q.pose();
  const auto& world = q.world();
  const Eigen::Quaterniond& r = pose.local[0];
  info->root.orientation = {float(r.x()), float(r.y()), float(r.z()), float(r.w())};
  info->root.position = {float(pose.root_position.x() * s), float(pose.root_position.y() * s), float(pose.root_position.z() * s)};
  if (local_rotations)
    for (int j = 0; j < n; ++j) {
      const Eigen::Quaterniond& l = pose.local[static_cast<std::size_t>(j)];
      local_rotations[j] = {float(l.x()), float(l.y()), float(l.z()), float(l.w())};
    }
  if (world_positions)
    for (int j = 0; j < n; ++j) {
      const Eigen::Vector3d& w = world.position[static_cast<std::size_t>(j)];
      world_positions[j] = {float(w.x() * s), float(w.y() * s), float(w.z() * s)};
    }
  return SB_OK;
  }
  SB_CATCH_ALL(p->error)
}

SPARSEBODY_API sb_status sb_pipeline_joint_count(sb_pipeline* p, int32_t* count) {
  namespace c = sparsebody::capi;
  SB_CHECK_PIPELINE(p);
  try {
  if (!count) return c::fail(p->error, SB_ERR_NULL, "sb_pipeline_joint_count: count is NULL");
  *count = p->impl->skeleton().size();
  return SB_OK;
  }
  SB_CATCH_ALL(p->error)
}

SPARSEBODY_API sb_status sb_pipeline_joint_name(sb_pipeline* p, int32_t joint, const char** name) {
  namespace c = sparsebody::capi;
  SB_CHECK_PIPELINE(p);
  try {
  if (!name) return c::fail(p->error, SB_ERR_NULL, "sb_pipeline_joint_name: name is NULL");
  *name = nullptr;
  const auto& s = p->impl->skeleton();
  if (joint < 0 || joint >= s.size())
    return c::fail(p->error, SB_ERR_INVALID_ARGUMENT, "sb_pipeline_joint_name: joint %d outside 0-%d", int(joint), s.size() - 1);
  *name = s.names[static_cast<std::size_t>(joint)].c_str();
  return SB_OK;
  }
  SB_CATCH_ALL(p->error)
}

SPARSEBODY_API sb_status sb_pipeline_joint_parents(sb_pipeline* p, int32_t* parents, int32_t capacity) {
  namespace c = sparsebody::capi;
  SB_CHECK_PIPELINE(p);
  try {
  if (!parents) return c::fail(p->error, SB_ERR_NULL, "sb_pipeline_joint_parents: parents is NULL");
  const auto& s = p->impl->skeleton();
  if (capacity < s.size())
    return c::fail(p->error, SB_ERR_CAPACITY, "sb_pipeline_joint_parents: capacity %d, the skeleton has %d joints", int(capacity), s.size());
  for (int j = 0; j < s.size(); ++j) parents[j] = s.parents[static_cast<std::size_t>(j)];
  return SB_OK;
  }
  SB_CATCH_ALL(p->error)
}

SPARSEBODY_API sb_status sb_pipeline_frame_rate(sb_pipeline* p, double* fps) {
  namespace c = sparsebody::capi;
  SB_CHECK_PIPELINE(p);
  try {
  if (!fps) return c::fail(p->error, SB_ERR_NULL, "sb_pipeline_frame_rate: fps is NULL");
  *fps = p->impl->frame_rate();
  return SB_OK;
  }
  SB_CATCH_ALL(p->error)
}

SPARSEBODY_API sb_status sb_pipeline_stream_events(sb_pipeline* p, int32_t* recentres, int32_t* controller_swaps,
                                                   int32_t* controllers_swapped) {
  namespace c = sparsebody::capi;
  SB_CHECK_PIPELINE(p);
  try {
  if (!recentres || !controller_swaps || !controllers_swapped)
    return c::fail(p->error, SB_ERR_NULL, "sb_pipeline_stream_events: an output pointer is NULL");
  *recentres = p->impl->recentres();
  *controller_swaps = p->impl->controller_swaps();
  *controllers_swapped = p->impl->controllers_swapped() ? 1 : 0;
  return SB_OK;
  }
  SB_CATCH_ALL(p->error)
}

SPARSEBODY_API sb_status sb_pipeline_stand_ups(sb_pipeline* p, int64_t* stand_ups) {
  namespace c = sparsebody::capi;
  SB_CHECK_PIPELINE(p);
  try {
  if (!stand_ups) return c::fail(p->error, SB_ERR_NULL, "sb_pipeline_stand_ups: stand_ups is NULL");
  *stand_ups = p->impl->stand_ups();
  return SB_OK;
  }
  SB_CATCH_ALL(p->error)
}

SPARSEBODY_API sb_status sb_pipeline_recalibrate(sb_pipeline* p) {
  SB_CHECK_PIPELINE(p);
  try {
  p->impl->recalibrate();
  return SB_OK;
  }
  SB_CATCH_ALL(p->error)
}

SPARSEBODY_API sb_status sb_pipeline_calibrate_frame(sb_pipeline* p, const sb_tracker_frame* frame) {
  namespace c = sparsebody::capi;
  SB_CHECK_PIPELINE(p);
  try {
  if (const sb_status s = c::check_frame(p->error, "sb_pipeline_calibrate_frame", frame); s != SB_OK) return s;
  if (!(frame->valid & SB_VALID_HEAD) || !c::finite_pose(frame->pose[0]) || !p->impl->calibrate(c::to_frame(*frame)))
    return c::fail(p->error, SB_ERR_INVALID_ARGUMENT, "sb_pipeline_calibrate_frame: the frame cannot be used (headset invalid, not finite or too low)");
  return SB_OK;
  }
  SB_CATCH_ALL(p->error)
}

SPARSEBODY_API sb_status sb_pipeline_set_joint_calibration(sb_pipeline* p, double scale) {
  namespace c = sparsebody::capi;
  SB_CHECK_PIPELINE(p);
  try {
  if (!(scale > 0.1 && scale < 10.0))  // NaN fails too
    return c::fail(p->error, SB_ERR_INVALID_ARGUMENT, "sb_pipeline_set_joint_calibration: scale %g outside (0.1, 10)", scale);
  p->impl->set_joint_calibration(scale);
  return SB_OK;
  }
  SB_CATCH_ALL(p->error)
}

SPARSEBODY_API sb_status sb_pipeline_calibration(sb_pipeline* p, sb_calibration_report* report) {
  namespace c = sparsebody::capi;
  SB_CHECK_PIPELINE(p);
  try {
  if (!report) return c::fail(p->error, SB_ERR_NULL, "sb_pipeline_calibration: report is NULL");
  if (report->struct_size != sizeof(sb_calibration_report))
    return c::fail(p->error, SB_ERR_STRUCT_SIZE, "sb_pipeline_calibration: report struct_size %u, expected %u", report->struct_size,
                   unsigned(sizeof(sb_calibration_report)));
  const auto& r = p->impl->calibration_report();
  const std::uint32_t size = report->struct_size;
  *report = sb_calibration_report{};
  report->struct_size = size;
  report->state = static_cast<int32_t>(r.status);
  report->source = static_cast<int32_t>(r.source);
  report->windows = r.windows;
  report->frames_used = r.first_frame >= 0 && r.last_frame >= r.first_frame ? r.last_frame - r.first_frame + 1 : 0;
  report->stature = r.stature;
  report->eye_height = r.eye_height;
  report->scale = r.scale;
  report->floor = r.floor;
  report->confidence = r.confidence;
  report->first_time = r.first_time;
  report->last_time = r.last_time;
  std::snprintf(report->message, sizeof report->message, "%s", r.message);
  report->grip_default[0] = r.grip_default[0] ? 1 : 0;
  report->grip_default[1] = r.grip_default[1] ? 1 : 0;
  report->grips_not_held = r.grips_not_held;
  return SB_OK;
  }
  SB_CATCH_ALL(p->error)
}

// ---- crowds ----------------------------------------------------------------------------------------

#define SB_CHECK_CROWD(c)                                                                                   \
  do {                                                                                                      \
    if (!(c)) return ::sparsebody::capi::fail(nullptr, SB_ERR_NULL, "%s: crowd is NULL", __func__);        \
    if (!::sparsebody::capi::live(c, ::sparsebody::capi::kCrowdTag))                                        \
      return ::sparsebody::capi::fail(nullptr, SB_ERR_BAD_HANDLE, "%s: not a live sb_crowd (foreign or destroyed)", __func__); \
  } while (0)

SPARSEBODY_API sb_status sb_crowd_create(const sb_weights* w, const sb_pipeline_config* cfg, int32_t users, sb_crowd** out) {
  namespace c = sparsebody::capi;
  namespace a = sparsebody::avatar;
  if (!out) return c::fail(nullptr, SB_ERR_NULL, "sb_crowd_create: out is NULL");
  *out = nullptr;
  if (const sb_status s = c::check_create(w, cfg, "sb_crowd_create"); s != SB_OK) return s;
  const int kind = cfg->pipeline;
  if (kind != SB_PIPELINE_LOBSTR && kind != SB_PIPELINE_N3P_DIRECT)
    return c::fail(nullptr, SB_ERR_INVALID_ARGUMENT, "sb_crowd_create: pipeline %d; a crowd is SB_PIPELINE_LOBSTR or SB_PIPELINE_N3P_DIRECT", kind);
  if (cfg->window_mode) return c::fail(nullptr, SB_ERR_INVALID_ARGUMENT, "sb_crowd_create: window_mode 1; a crowd streams");
  if (users < 1 || users > sparsebody::nn::kBatchMax)
    return c::fail(nullptr, SB_ERR_INVALID_ARGUMENT, "sb_crowd_create: %d users, expected 1-%d", int(users), sparsebody::nn::kBatchMax);
  try {
    auto h = std::make_unique<sb_crowd>();
    h->kind = kind;
    h->users = users;
    c::with_storage(w->storage, [&](auto tag) {
      using W = typename decltype(tag)::type;
      using L = typename c::Builds<W>::LoBSTr;
      using N = typename c::Builds<W>::N3PDirect;
      if (kind == SB_PIPELINE_LOBSTR)
        h->impl = std::make_unique<c::CrowdModel<L, a::LoBSTrBatch<L>>>(c::lobstr_of<W>(*w), users, c::lobstr_config(*cfg));
      else
        h->impl = std::make_unique<c::CrowdModel<N, a::N3PBatch<N>>>(c::n3p_of<W>(*w), users, c::n3p_config(*cfg));
    });
    h->user = std::make_unique<sb_pipeline[]>(static_cast<std::size_t>(users));
    h->view = std::make_unique<c::PipelineBase*[]>(static_cast<std::size_t>(users));
    for (int i = 0; i < users; ++i) {
      sb_pipeline& u = h->user[static_cast<std::size_t>(i)];
      u.kind = kind;
      u.crowd = h.get();
      u.impl = h->impl->user_view(i);
      h->view[static_cast<std::size_t>(i)] = u.impl.get();
    }
    *out = h.release();
    return SB_OK;
  }
  SB_CATCH_ALL(nullptr)
}

SPARSEBODY_API sb_status sb_crowd_destroy(sb_crowd* cr) {
  namespace c = sparsebody::capi;
  if (!cr) return SB_OK;
  SB_CHECK_CROWD(cr);
  try {
    for (int i = 0; i < cr->users; ++i) cr->user[static_cast<std::size_t>(i)].tag = c::kDeadTag;
    cr->tag = c::kDeadTag;
    delete cr;
    return SB_OK;
  }
  SB_CATCH_ALL(nullptr)
}

SPARSEBODY_API sb_status sb_crowd_size(sb_crowd* cr, int32_t* users) {
  namespace c = sparsebody::capi;
  SB_CHECK_CROWD(cr);
  if (!users) return c::fail(cr->error, SB_ERR_NULL, "sb_crowd_size: users is NULL");
  *users = cr->users;
  return SB_OK;
}

SPARSEBODY_API sb_status sb_crowd_push(sb_crowd* cr, const sb_tracker_frame* frames, int32_t count, int32_t* steps) {
  namespace c = sparsebody::capi;
  SB_CHECK_CROWD(cr);
  try {
  if (!frames) return c::fail(cr->error, SB_ERR_NULL, "sb_crowd_push: frames is NULL");
  if (count != cr->users)
    return c::fail(cr->error, SB_ERR_INVALID_ARGUMENT, "sb_crowd_push: %d frames for a crowd of %d users", int(count), cr->users);
  sparsebody::trackers::TrackerFrame f[sparsebody::nn::kBatchMax];
  int bad_user = -1, bad = -1;
  for (int i = 0; i < count; ++i) {
    char fn[64];
    std::snprintf(fn, sizeof fn, "sb_crowd_push: user %d", i);
    if (const sb_status s = c::check_frame(cr->error, fn, frames + i); s != SB_OK) return s;
    if (bad_user < 0 && (bad = c::nonfinite_tracker(frames[i])) >= 0) bad_user = i;
    f[i] = c::to_frame(frames[i]);
  }
  int k[sparsebody::nn::kBatchMax];
  std::uint32_t flags[sparsebody::nn::kBatchMax];
  cr->impl->push(f, cr->view.get(), k, flags);
  for (int i = 0; i < count; ++i) {
    sb_pipeline& u = cr->user[static_cast<std::size_t>(i)];
    u.steps = k[i];
    u.flags = flags[i];
    u.pushed = true;
    if (steps) steps[i] = k[i];
  }
  if (bad_user >= 0)
    return c::fail(cr->error, SB_NONFINITE_POSE, "sb_crowd_push: user %d: tracker %d (%s) is flagged valid but not finite: treated as lost",
                   bad_user, bad, sparsebody::trackers::tracker_name(bad));
  return SB_OK;
  }
  SB_CATCH_ALL(cr->error)
}

SPARSEBODY_API sb_status sb_crowd_user(sb_crowd* cr, int32_t i, sb_pipeline** user) {
  namespace c = sparsebody::capi;
  SB_CHECK_CROWD(cr);
  if (!user) return c::fail(cr->error, SB_ERR_NULL, "sb_crowd_user: user is NULL");
  *user = nullptr;
  if (i < 0 || i >= cr->users) return c::fail(cr->error, SB_ERR_INVALID_ARGUMENT, "sb_crowd_user: user %d outside 0-%d", int(i), cr->users - 1);
  *user = &cr->user[static_cast<std::size_t>(i)];
  return SB_OK;
}

}  // extern "C"

#undef SB_CHECK_CROWD

#undef SB_CHECK_PIPELINE
#undef SB_CATCH_ALL
