// Per-frame latency of the LoBSTr avatar pipeline (features, network, heads, contacts, leg and arm
// IK), streaming and window modes, compact (H=256, the shipped weights) and paper (H=1024, random
// weights with the shipped file's metadata) configurations. Input: the CMU clip of the parity
// golden, 30 Hz, one model step per pushed frame.
// Targets on the 2-core dev machine: compact streaming <= 15 us, paper streaming <= 450 us.
// Run: build/bench/bench_lobstr --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <array>
#include <fstream>

#include <benchmark/benchmark.h>

#include "nn/random_tables.hpp"
#include "sparsebody/avatar/lobstr_pipeline.hpp"

using namespace sparsebody;

namespace {

std::vector<trackers::TrackerFrame> clip_frames() {
  std::ifstream f(std::string(SPARSEBODY_PIPELINE_GOLDEN_DIR) + "/lobstr_pipeline_small.golden.json");
  const auto g = nlohmann::json::parse(f);
  std::vector<trackers::TrackerFrame> out;
  for (std::size_t i = 0; i < g["positions"].size(); ++i) {
    trackers::TrackerFrame fr;
    for (int k = 0; k < 4; ++k) {
      const auto& P = g["positions"][i][k];
      const auto& Q = g["quaternions_xyzw"][i][k];
      fr.pose[k].position = {P[0].get<float>(), P[1].get<float>(), P[2].get<float>()};
      fr.pose[k].orientation = {Q[0].get<float>(), Q[1].get<float>(), Q[2].get<float>(), Q[3].get<float>()};
      fr.valid[k] = true;
    }
    out.push_back(fr);
  }
  return out;
}

template <int H, typename Wt = float>
using Pipe = avatar::LoBSTrPipeline<float, H, 128, Wt>;

template <int H, typename Wt = float>
std::shared_ptr<const typename Pipe<H, Wt>::Weights> weights() {
  using W = typename Pipe<H, Wt>::Weights;
  if constexpr (H == 256) {
    return Pipe<H, Wt>::load(SPARSEBODY_LOBSTR_WEIGHTS);
  } else {  // paper size: random tensors, the shipped file's metadata and input normalisation
    io::WeightsDocument doc = io::read_weights_file(SPARSEBODY_LOBSTR_WEIGHTS);
    doc.tensors = sparsebody_test::random_lobstr_table(H, 128, 11);
    return W::from_document(std::move(doc), networks::kLoBSTrKind);
  }
}

template <int H, typename Wt = float>
void BM_Pipeline(benchmark::State& st) {
  const bool window = st.range(0) != 0;
  avatar::LoBSTrConfig cfg;
  cfg.mode = window ? avatar::RunMode::Window : avatar::RunMode::Streaming;
  Pipe<H, Wt> p(weights<H, Wt>(), cfg);
  const auto frames = clip_frames();
  std::size_t i = 0;
  double t = 0;
  long steps = 0;
  for (auto _ : st) {
    if (i == frames.size()) {  // loop the clip: restart outside the timed region
      st.PauseTiming();
      p.reset();
      i = 0;
      st.ResumeTiming();
    }
    trackers::TrackerFrame f = frames[i++];
    f.time = t;
    t += 1.0 / 30.0;
    steps += p.push(f);
    benchmark::DoNotOptimize(p.pose().local.data());
    benchmark::ClobberMemory();
  }
  st.counters["steps_per_frame"] = double(steps) / double(st.iterations());
  st.SetLabel(std::string(H == 256 ? "compact H=256" : "paper H=1024") + (window ? ", window 30" : ", streaming"));
}

// The network step alone (same weights, the pipeline's features as input): the pipeline's own cost
// is the difference, measured in the same run.
template <int H, typename Wt = float>
void BM_NetworkOnly(benchmark::State& st) {
  Pipe<H> p(weights<H>());
  nn::Network<typename Pipe<H, Wt>::Net> net(weights<H, Wt>());
  const auto frames = clip_frames();
  std::vector<std::array<float, 37>> xs;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    auto f = frames[i];
    f.time = i / 30.0;
    p.push(f);
    std::array<float, 37> x;
    std::copy(p.features(), p.features() + 37, x.begin());
    xs.push_back(x);
  }
  std::size_t i = 0;
  for (auto _ : st) {
    const float* y = net.step(xs[i].data());
    i = (i + 1) % xs.size();
    benchmark::DoNotOptimize(y);
    benchmark::ClobberMemory();
  }
  st.SetLabel(H == 256 ? "network step only, H=256" : "network step only, H=1024");
}

BENCHMARK_TEMPLATE(BM_NetworkOnly, 256)->Name("lobstr/compact/network_only")->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_NetworkOnly, 1024)->Name("lobstr/paper/network_only")->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_Pipeline, 256)->Name("lobstr/compact/streaming")->Arg(0)->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_Pipeline, 256)->Name("lobstr/compact/window")->Arg(1)->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_Pipeline, 1024)->Name("lobstr/paper/streaming")->Arg(0)->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_Pipeline, 1024)->Name("lobstr/paper/window")->Arg(1)->Unit(benchmark::kMicrosecond)->Iterations(200);
// Smaller weight storage (nn/half.hpp, nn/int8.hpp): same pipeline, f16 or int8 network weights.
BENCHMARK_TEMPLATE(BM_NetworkOnly, 256, nn::q8)->Name("lobstr/compact/network_only_q8")->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_NetworkOnly, 1024, nn::q8)->Name("lobstr/paper/network_only_q8")->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_Pipeline, 256, nn::f16)->Name("lobstr/compact/streaming_f16")->Arg(0)->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_Pipeline, 256, nn::q8)->Name("lobstr/compact/streaming_q8")->Arg(0)->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_Pipeline, 1024, nn::f16)->Name("lobstr/paper/streaming_f16")->Arg(0)->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_Pipeline, 1024, nn::q8)->Name("lobstr/paper/streaming_q8")->Arg(0)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
