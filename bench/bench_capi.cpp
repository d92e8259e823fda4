// What the C API (include/sparsebody/c/) adds per frame: push + read of one 30 Hz frame through
// sb_pipeline_push / sb_pipeline_read against the same C++ calls (push, then the pose copied into
// the same float arrays: local rotations, world positions in the user's size), same run, same
// frames, the API compiled into this binary with the same flags (SPARSEBODY_C_STATIC).
//   BM_Paired/<pipeline>  every iteration times one C++ frame and one C frame (two instances fed the
//                         same frame): counters cpp_us, c_us and overhead_us = their difference, as
//                         medians over the iterations, which a noisy shared machine cannot skew;
//   BM_Cpp/<pipeline>, BM_C/<pipeline>  each alone (Google Benchmark's own timing).
// pipeline: 0 LoBSTr compact, 1 Neural3Points direct, 2 Neural3Points physics; float weights.
//   BM_CInt8/<pipeline>   BM_C with int8 weights (sb_weights_load_storage, SB_STORAGE_INT8).
// Input: a synthetic user walking a circle and waving, with a pelvis tracker (no data files).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <vector>

#include "sparsebody/c/sparsebody_c_impl.hpp"

using namespace sparsebody;

namespace {

trackers::TrackerFrame frame(long t) {
  const double a = 0.02 * t, s = std::sin(0.3 * t);
  trackers::TrackerFrame f;
  f.time = t / 30.0;
  const Eigen::Vector3d c(1.5 * std::sin(a), 0, 1.5 * std::cos(a));
  const Eigen::Quaterniond yaw(Eigen::AngleAxisd(a + M_PI, Eigen::Vector3d::UnitY()));  // OpenXR: looking along -Z
  const Eigen::Vector3d pos[4] = {c + Eigen::Vector3d(0, 1.62, 0), c + yaw * Eigen::Vector3d(-0.35, 1.0 + 0.2 * s, -0.2),
                                  c + yaw * Eigen::Vector3d(0.35, 1.0 - 0.2 * s, -0.2), c + Eigen::Vector3d(0, 1.0, 0)};
  for (int k = 0; k < 4; ++k) {
    f.pose[k].position = trackers::to_xr(pos[k]);
    f.pose[k].orientation = trackers::to_xr(yaw);
    f.valid[k] = true;
  }
  return f;
}

sb_tracker_frame to_c(const trackers::TrackerFrame& f) {
  sb_tracker_frame c{};
  c.struct_size = sizeof c;
  c.time = f.time;
  for (int k = 0; k < 4; ++k) {
    const auto& p = f.pose[k];
    c.pose[k].orientation = {p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w};
    c.pose[k].position = {p.position.x, p.position.y, p.position.z};
    if (f.valid[k]) c.valid |= 1u << k;
  }
  return c;
}

// The C++ read a C caller gets from sb_pipeline_read: the pose as floats, positions x user scale.
template <class P>
void copy_pose(const P& p, sb_quatf* rot, sb_vec3f* pos) {
  if (!p.has_output()) return;
  const double s = p.user_scale();
  const int n = p.skeleton().size();
  for (int j = 0; j < n; ++j) {
    const auto& q = p.pose().local[static_cast<std::size_t>(j)];
    const auto& w = p.world().position[static_cast<std::size_t>(j)];
    rot[j] = {float(q.x()), float(q.y()), float(q.z()), float(q.w())};
    pos[j] = {float(w.x() * s), float(w.y() * s), float(w.z() * s)};
  }
  benchmark::DoNotOptimize(rot[0]);
  benchmark::DoNotOptimize(pos[n - 1]);
}

struct Fixture {
  sb_weights* lobstr = nullptr;
  sb_weights* n3p = nullptr;
  sb_weights* lobstr_q8 = nullptr;
  sb_weights* n3p_q8 = nullptr;
  Fixture() {
    sb_weights_load(SB_MODEL_LOBSTR, SPARSEBODY_LOBSTR_WEIGHTS, &lobstr);
    sb_weights_load(SB_MODEL_N3P, SPARSEBODY_N3P_WEIGHTS, &n3p);
    sb_weights_load_storage(SB_MODEL_LOBSTR, SPARSEBODY_LOBSTR_WEIGHTS, SB_STORAGE_INT8, &lobstr_q8);
    sb_weights_load_storage(SB_MODEL_N3P, SPARSEBODY_N3P_WEIGHTS, SB_STORAGE_INT8, &n3p_q8);
  }
};
const Fixture& fixture() {
  static const Fixture f;
  return f;
}

sb_pipeline* c_pipeline(int kind, bool int8 = false) {
  sb_pipeline_config c;
  sb_pipeline_config_init(&c, kind);
  sb_pipeline* p = nullptr;
  const Fixture& w = fixture();
  sb_pipeline_create(kind == SB_PIPELINE_LOBSTR ? (int8 ? w.lobstr_q8 : w.lobstr) : (int8 ? w.n3p_q8 : w.n3p), &c, &p);
  return p;
}

// The C++ pipeline of `kind`, on the same weights objects as the C one.
template <class F>
void with_cpp(int kind, F&& f) {
  if (kind == SB_PIPELINE_LOBSTR) {
    capi::LoBSTr p(fixture().lobstr->lobstr);
    f(p);
  } else if (kind == SB_PIPELINE_N3P_DIRECT) {
    capi::N3PDirect p(fixture().n3p->n3p);
    f(p);
  } else {
    capi::N3PPhysics p(fixture().n3p->n3p);
    f(p);
  }
}

constexpr long kWarm = 60;  // 2 s: past the first frames and the model's start

int kind_of(const benchmark::State& s) { return static_cast<int>(s.range(0)) + 1; }
bool ready(benchmark::State& s) {
  if (fixture().lobstr && fixture().n3p) return true;
  s.SkipWithError("default weights not found under examples/weights");
  return false;
}

void BM_Paired(benchmark::State& state) {
  if (!ready(state)) return;
  const int kind = kind_of(state);
  with_cpp(kind, [&](auto& cpp) {
    sb_pipeline* c = c_pipeline(kind);
    const int n = cpp.skeleton().size();
    std::vector<sb_quatf> rot(static_cast<std::size_t>(n)), rot_c(rot);
    std::vector<sb_vec3f> pos(static_cast<std::size_t>(n)), pos_c(pos);
    sb_pose_info info{};
    info.struct_size = sizeof info;
    long t = 0;
    for (; t < kWarm; ++t) {
      const auto f = frame(t);
      const auto fc = to_c(f);
      cpp.push(f);
      sb_pipeline_push(c, &fc, nullptr);
    }
    std::vector<double> a, b;
    a.reserve(1 << 16);
    b.reserve(1 << 16);
    using clock = std::chrono::steady_clock;
    for (auto _ : state) {
      const auto f = frame(t);
      const auto fc = to_c(f);  // the frame in each side's type, built outside the timed parts
      ++t;
      // alternate which side runs first, so neither always finds the caches the other left
      const bool cpp_first = t & 1;
      double dt[2];
      for (int side = 0; side < 2; ++side) {
        const bool run_cpp = (side == 0) == cpp_first;
        const auto t0 = clock::now();
        if (run_cpp) {
          cpp.push(f);
          copy_pose(cpp, rot.data(), pos.data());
        } else {
          sb_pipeline_push(c, &fc, nullptr);
          sb_pipeline_read(c, &info, rot_c.data(), pos_c.data(), n);
          benchmark::DoNotOptimize(rot_c[0]);
        }
        dt[run_cpp ? 0 : 1] = std::chrono::duration<double, std::micro>(clock::now() - t0).count();
      }
      if (a.size() < a.capacity()) {
        a.push_back(dt[0]);
        b.push_back(dt[1]);
      }
    }
    auto median = [](std::vector<double> v) {
      if (v.empty()) return 0.0;
      std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
      return v[v.size() / 2];
    };
    std::vector<double> d(a.size());
    for (std::size_t i = 0; i < a.size(); ++i) d[i] = b[i] - a[i];
    state.counters["cpp_us"] = median(a);
    state.counters["c_us"] = median(b);
    state.counters["overhead_us"] = median(d);
    sb_pipeline_destroy(c);
  });
}

void BM_Cpp(benchmark::State& state) {
  if (!ready(state)) return;
  with_cpp(kind_of(state), [&](auto& cpp) {
    const int n = cpp.skeleton().size();
    std::vector<sb_quatf> rot(static_cast<std::size_t>(n));
    std::vector<sb_vec3f> pos(static_cast<std::size_t>(n));
    long t = 0;
    for (; t < kWarm; ++t) cpp.push(frame(t));
    for (auto _ : state) {
      cpp.push(frame(t++));
      copy_pose(cpp, rot.data(), pos.data());
    }
  });
}

void c_frames(benchmark::State& state, bool int8) {
  if (!ready(state)) return;
  const int kind = kind_of(state);
  sb_pipeline* c = c_pipeline(kind, int8);
  if (!c) {
    state.SkipWithError("no pipeline (int8 weights not loaded)");
    return;
  }
  int32_t n = 0;
  sb_pipeline_joint_count(c, &n);
  std::vector<sb_quatf> rot(static_cast<std::size_t>(n));
  std::vector<sb_vec3f> pos(static_cast<std::size_t>(n));
  sb_pose_info info{};
  info.struct_size = sizeof info;
  long t = 0;
  for (; t < kWarm; ++t) {
    const auto fc = to_c(frame(t));
    sb_pipeline_push(c, &fc, nullptr);
  }
  for (auto _ : state) {
    const auto fc = to_c(frame(t++));
    sb_pipeline_push(c, &fc, nullptr);
    sb_pipeline_read(c, &info, rot.data(), pos.data(), n);
    benchmark::DoNotOptimize(rot[0]);
  }
  sb_pipeline_destroy(c);
}
void BM_C(benchmark::State& state) { c_frames(state, false); }
void BM_CInt8(benchmark::State& state) { c_frames(state, true); }

}  // namespace

BENCHMARK(BM_Paired)->DenseRange(0, 2)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Cpp)->DenseRange(0, 2)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_C)->DenseRange(0, 2)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_CInt8)->DenseRange(0, 2)->Unit(benchmark::kMicrosecond);

BENCHMARK_MAIN();
