// Per-frame cost of Neural3Points at the paper's sizes (G_sig 64, G_lo 128, G_up 128 hidden, 3 GRU
// layers each), float, on the default weights:
//   BM_N3PPredictorStep     one Eq. (2) step: 3 tracker transforms, 3 networks, heading update, pose
//   BM_N3PPredictorHmdOnly  the same with both controllers from o* (§8.2)
//   BM_N3PPredictorStepF16  one step with the weights stored as float16 (half the bytes to read)
//   BM_N3PPredictorStepQ8   one step with int8 weights (nn/int8.hpp: a quarter of the bytes)
//   BM_N3PNet/{0,1,2}       G_sig, G_lo, G_up alone (one network step each)
//   BM_N3PPipelineFrame     a whole 30 Hz frame of the direct-mode pipeline (resampling, checks,
//                           calibration, predictor, foot pinning and arm IK); F16 and Q8 variants
//   crowd/*                 N users per frame (users:N): one N3PBatch step (batched:1) against N
//                           pipeline steps (batched:0), model-rate frames; per_user = time / N
// Input: a synthetic user walking a circle and waving (no data files needed besides the weights).
#include <benchmark/benchmark.h>

#include <cmath>
#include <memory>
#include <vector>

#include "sparsebody/avatar/n3p_batch.hpp"
#include "sparsebody/avatar/n3p_direct.hpp"

#include "n3p_default_weights.hpp"

using namespace sparsebody;

namespace {
using Pipeline = avatar::N3PDirect;

template <class P = Pipeline>
const typename P::Weights* weights() {
  return n3p_default_weights<P>();
}

trackers::TrackerFrame frame(int t) {
  const double a = 0.02 * t, s = std::sin(0.3 * t);
  trackers::TrackerFrame f;
  f.time = t / 30.0;
  const Eigen::Vector3d c(1.5 * std::sin(a), 0, 1.5 * std::cos(a));
  const Eigen::Quaterniond yaw(Eigen::AngleAxisd(a + M_PI / 2, Eigen::Vector3d::UnitY()));
  const Eigen::Vector3d pos[3] = {c + Eigen::Vector3d(0, 1.38, 0), c + yaw * Eigen::Vector3d(0.35, 1.0 + 0.2 * s, -0.2),
                                  c + yaw * Eigen::Vector3d(-0.35, 1.0 - 0.2 * s, -0.2)};
  for (int k = 0; k < 3; ++k) {
    f.pose[k].position = trackers::to_xr(pos[k]);
    f.pose[k].orientation = trackers::to_xr(yaw);
    f.valid[k] = true;
  }
  return f;
}

features::n3p::TrackerSet samples(int t) {
  const auto f = frame(t);
  features::n3p::TrackerSet o;
  for (int k = 0; k < 3; ++k)
    o[k] = features::n3p::TrackerSample::from(trackers::to_eigen(f.pose[k].position),
                                              trackers::to_eigen(f.pose[k].orientation).toRotationMatrix());
  return o;
}

template <class P>
void predictor(benchmark::State& state, bool hmd_only) {
  using Predictor = typename P::Predictor;
  const auto* w = weights<P>();
  if (!w) {
    state.SkipWithError("default weights not found: " SPARSEBODY_N3P_WEIGHTS "_*.json");
    return;
  }
  Predictor p(*w);
  std::vector<features::n3p::TrackerSet> in;
  for (int t = 0; t < 300; ++t) in.push_back(samples(t));
  const std::array<bool, 3> present{true, !hmd_only, !hmd_only};
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(p.step(in[i], present));
    benchmark::DoNotOptimize(p.pose().root_position.data());
    if (++i == in.size()) i = 0;
  }
  state.SetItemsProcessed(state.iterations());
}
void BM_N3PPredictorStep(benchmark::State& s) { predictor<Pipeline>(s, false); }
void BM_N3PPredictorHmdOnly(benchmark::State& s) { predictor<Pipeline>(s, true); }
void BM_N3PPredictorStepF16(benchmark::State& s) { predictor<avatar::N3PDirectF16>(s, false); }
void BM_N3PPredictorStepQ8(benchmark::State& s) { predictor<avatar::N3PDirectQ8>(s, false); }

template <class Net, class WPtr>
void net_step(benchmark::State& state, const WPtr& w) {
  nn::Network<Net> n(w);
  std::vector<float> x(Net::in_size, 0.1f);
  for (auto _ : state) benchmark::DoNotOptimize(n.step(x.data()));
}
void BM_N3PNet(benchmark::State& state) {
  const auto* w = weights<Pipeline>();
  if (!w) {
    state.SkipWithError("default weights not found");
    return;
  }
  using P = Pipeline::Predictor;
  if (state.range(0) == 0) net_step<typename P::SigNet>(state, w->sig);
  if (state.range(0) == 1) net_step<typename P::LoNet>(state, w->lo);
  if (state.range(0) == 2) net_step<typename P::UpNet>(state, w->up);
  state.SetBytesProcessed(state.iterations() *
                          static_cast<int64_t>(state.range(0) == 0 ? w->sig->bytes() : state.range(0) == 1 ? w->lo->bytes() : w->up->bytes()));
}

template <class P>
void pipeline_frame(benchmark::State& state) {
  const auto* w = weights<P>();
  if (!w) {
    state.SkipWithError("default weights not found");
    return;
  }
  P p(*w);
  int t = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(p.push(frame(t++)));
    benchmark::DoNotOptimize(p.world().position.data());
  }
  state.SetItemsProcessed(state.iterations());
}
template <class P>
void BM_Crowd(benchmark::State& state) {
  const auto* w = weights<P>();
  if (!w) {
    state.SkipWithError("default weights not found");
    return;
  }
  const int n = static_cast<int>(state.range(0));
  const int mode = static_cast<int>(state.range(1));  // batched (1, 3) or singles (0, 2); push (2, 3) or step (0, 1)
  const bool batched = (mode & 1) != 0, push = mode >= 2;
  avatar::N3PBatch<P> crowd(*w, n);
  std::vector<std::unique_ptr<P>> single;
  for (int u = 0; u < n; ++u) single.push_back(std::make_unique<P>(*w));
  std::vector<trackers::TrackerFrame> now(static_cast<std::size_t>(n));
  int t = 0;
  for (auto _ : state) {
    for (int u = 0; u < n; ++u) {
      now[u] = frame(t + 17 * u);
      now[u].time = t / 30.0;
    }
    ++t;
    if (batched) {
      if (push) crowd.push(now.data());
      else crowd.step(now.data());
      benchmark::DoNotOptimize(crowd[n - 1].world().position.data());
    } else {
      for (int u = 0; u < n; ++u) push ? void(single[u]->push(now[u])) : single[u]->step(now[u]);
      benchmark::DoNotOptimize(single[n - 1]->world().position.data());
    }
    benchmark::ClobberMemory();
  }
  state.counters["per_user"] = benchmark::Counter(n, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
void BM_N3PPipelineFrame(benchmark::State& s) { pipeline_frame<Pipeline>(s); }
void BM_N3PPipelineFrameF16(benchmark::State& s) { pipeline_frame<avatar::N3PDirectF16>(s); }
void BM_N3PPipelineFrameQ8(benchmark::State& s) { pipeline_frame<avatar::N3PDirectQ8>(s); }
}  // namespace

BENCHMARK(BM_N3PPredictorStep);
BENCHMARK(BM_N3PPredictorHmdOnly);
BENCHMARK(BM_N3PPredictorStepF16);
BENCHMARK(BM_N3PPredictorStepQ8);
BENCHMARK(BM_N3PNet)->Arg(0)->Arg(1)->Arg(2);
BENCHMARK(BM_N3PPipelineFrame);
BENCHMARK(BM_N3PPipelineFrameF16);
BENCHMARK(BM_N3PPipelineFrameQ8);
BENCHMARK_TEMPLATE(BM_Crowd, avatar::N3PDirect)->Name("crowd/n3p_direct")->ArgsProduct({{1, 4, 16, 64}, {0, 1}})
    ->ArgNames({"users", "batched"})->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_Crowd, avatar::N3PDirectQ8)->Name("crowd/n3p_direct_q8")->ArgsProduct({{1, 4, 16, 64}, {0, 1}})
    ->ArgNames({"users", "batched"})->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_Crowd, avatar::N3PDirectF16)->Name("crowd/n3p_direct_f16")->ArgsProduct({{1, 4, 16, 64}, {0, 1}})
    ->ArgNames({"users", "batched"})->Unit(benchmark::kMicrosecond);
// The same through push (each user's stream), 16 users: batched 3 against singles 2.
BENCHMARK_TEMPLATE(BM_Crowd, avatar::N3PDirect)->Name("crowd_push/n3p_direct")->ArgsProduct({{16}, {2, 3}})
    ->ArgNames({"users", "batched"})->Unit(benchmark::kMicrosecond);
BENCHMARK_MAIN();
