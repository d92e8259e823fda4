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
#include "sparsebody/avatar/lobstr_batch.hpp"
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

// P: a shipped configuration (avatar::LoBSTrCompact, LoBSTrPaper, their F16 / Q8 storage).
template <class P>
std::shared_ptr<const typename P::Weights> weights() {
  if constexpr (P::kHidden == 256) {
    return P::load(SPARSEBODY_LOBSTR_WEIGHTS);
  } else {  // paper size: random tensors, the shipped file's metadata and input normalisation
    io::WeightsDocument doc = io::read_weights_file(SPARSEBODY_LOBSTR_WEIGHTS);
    doc.tensors = sparsebody_test::random_lobstr_table(P::kHidden, P::kLatent, 11);
    return P::Weights::from_document(std::move(doc), networks::kLoBSTrKind);
  }
}

template <class P>
void BM_Pipeline(benchmark::State& st) {
  const bool window = st.range(0) != 0;
  avatar::LoBSTrConfig cfg;
  cfg.mode = window ? avatar::RunMode::Window : avatar::RunMode::Streaming;
  P p(weights<P>(), cfg);
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
  st.SetLabel(std::string(P::kHidden == 256 ? "compact H=256" : "paper H=1024") + (window ? ", window 30" : ", streaming"));
}

// The network step alone (same weights, the pipeline's features as input): the pipeline's own cost
// is the difference, measured in the same run. Features from the float pipeline of the same size.
template <class P, class FloatP>
void BM_NetworkOnly(benchmark::State& st) {
  FloatP p(weights<FloatP>());
  nn::Network<typename P::Net> net(weights<P>());
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
  st.SetLabel(P::kHidden == 256 ? "network step only, H=256" : "network step only, H=1024");
}

// N users per frame (st.range(0)), each on the clip from its own start frame: one LoBSTrBatch
// step (batched = 1) against N LoBSTrPipeline steps (batched = 0) on the same frames; batched = 3
// / 2: the same through push (each user's stream: resampling, recentre and swap checks). The time is
// per frame for all N users; per_user divides it by N.
template <class P>
void BM_Crowd(benchmark::State& st) {
  const int n = static_cast<int>(st.range(0));
  const int mode = static_cast<int>(st.range(1));  // batched (1, 3) or singles (0, 2); push (2, 3) or step (0, 1)
  const bool batched = (mode & 1) != 0, push = mode >= 2;
  const auto w = weights<P>();
  avatar::LoBSTrBatch<P> crowd(w, n);
  std::vector<std::unique_ptr<P>> single;
  for (int u = 0; u < n; ++u) single.push_back(std::make_unique<P>(w));
  const auto frames = clip_frames();
  std::vector<trackers::TrackerFrame> now(static_cast<std::size_t>(n));
  long t = 0;
  for (auto _ : st) {
    for (int u = 0; u < n; ++u) {
      now[u] = frames[(static_cast<std::size_t>(t) + 13 * u) % frames.size()];
      now[u].time = t / 30.0;
    }
    ++t;
    if (batched) {
      if (push) crowd.push(now.data());
      else crowd.step(now.data());
      benchmark::DoNotOptimize(crowd[n - 1].pose().local.data());
    } else {
      for (int u = 0; u < n; ++u) push ? void(single[u]->push(now[u])) : single[u]->step(now[u]);
      benchmark::DoNotOptimize(single[n - 1]->pose().local.data());
    }
    benchmark::ClobberMemory();
  }
  st.counters["per_user"] = benchmark::Counter(n, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);  // s
  st.SetLabel(std::string(batched ? "one batch " : "N single ") + (push ? "push" : "step") + ", " + std::to_string(n) + " users");
}

using avatar::LoBSTrCompact;
using avatar::LoBSTrCompactF16;
using avatar::LoBSTrCompactQ8;
using avatar::LoBSTrPaper;
using avatar::LoBSTrPaperF16;
using avatar::LoBSTrPaperQ8;
BENCHMARK_TEMPLATE(BM_NetworkOnly, LoBSTrCompact, LoBSTrCompact)->Name("lobstr/compact/network_only")->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_NetworkOnly, LoBSTrPaper, LoBSTrPaper)->Name("lobstr/paper/network_only")->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_Pipeline, LoBSTrCompact)->Name("lobstr/compact/streaming")->Arg(0)->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_Pipeline, LoBSTrCompact)->Name("lobstr/compact/window")->Arg(1)->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_Pipeline, LoBSTrPaper)->Name("lobstr/paper/streaming")->Arg(0)->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_Pipeline, LoBSTrPaper)->Name("lobstr/paper/window")->Arg(1)->Unit(benchmark::kMicrosecond)->Iterations(200);
// Smaller weight storage (nn/half.hpp, nn/int8.hpp): same pipeline, f16 or int8 network weights.
BENCHMARK_TEMPLATE(BM_NetworkOnly, LoBSTrCompactQ8, LoBSTrCompact)->Name("lobstr/compact/network_only_q8")->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_NetworkOnly, LoBSTrPaperQ8, LoBSTrPaper)->Name("lobstr/paper/network_only_q8")->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_Pipeline, LoBSTrCompactF16)->Name("lobstr/compact/streaming_f16")->Arg(0)->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_Pipeline, LoBSTrCompactQ8)->Name("lobstr/compact/streaming_q8")->Arg(0)->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_Pipeline, LoBSTrPaperF16)->Name("lobstr/paper/streaming_f16")->Arg(0)->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_Pipeline, LoBSTrPaperQ8)->Name("lobstr/paper/streaming_q8")->Arg(0)->Unit(benchmark::kMicrosecond);

}  // namespace

#define SPARSEBODY_CROWD(P, name)                                                                              \
  BENCHMARK_TEMPLATE(BM_Crowd, P)->Name(name)->ArgsProduct({{1, 4, 16, 64}, {0, 1}})->ArgNames({"users", "batched"}) \
      ->Unit(benchmark::kMicrosecond)
SPARSEBODY_CROWD(LoBSTrCompact, "crowd/lobstr_compact");
SPARSEBODY_CROWD(LoBSTrCompactQ8, "crowd/lobstr_compact_q8");
SPARSEBODY_CROWD(LoBSTrCompactF16, "crowd/lobstr_compact_f16");
BENCHMARK_TEMPLATE(BM_Crowd, LoBSTrCompact)->Name("crowd_push/lobstr_compact")->ArgsProduct({{16}, {2, 3}})
    ->ArgNames({"users", "batched"})->Unit(benchmark::kMicrosecond);

BENCHMARK_MAIN();
