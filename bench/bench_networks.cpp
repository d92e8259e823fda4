// Per-step latency of the papers' networks (float, one instance, random weights), each with the
// weight bytes it streams per step and the achieved bandwidth, against
//  - LibTorch (same network, one thread, inference mode) when built with it, and
//  - a plain SIMD read of the same number of bytes: the memory-bandwidth floor for these sizes, and
//  - "paired/": each network step interleaved with a plain read of its own weight buffers (the
//    robust step/read ratio on a noisy machine), and
//  - "limit/": the build's arithmetic limit for the same multiply-adds (compute_limit.hpp), the
//    FLOP floor beside the memory floor.
// Run: build/bench/bench_networks --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// The storage table (float / f16 / q8 for every paper network, speed-ups printed at the end), e.g.
// for a -DSPARSEBODY_MARCH=x86-64-v3 build beside the native one:
//   build/bench/bench_networks --benchmark_filter='^sparsebody/' --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "compute_limit.hpp"
#include "nn/packed_q8.hpp"
#include "nn/random_tables.hpp"
#include "ratio_report.hpp"
#include "sparsebody/core/aligned_buffer.hpp"
#include "sparsebody/io/base64.hpp"
#include "sparsebody/networks/lobstr_net.hpp"
#include "sparsebody/networks/n3p_predictor_net.hpp"
#include "sparsebody/networks/policy_nets.hpp"
#include "sparsebody/nn/batch.hpp"
#include "sparsebody/nn/network.hpp"
#include "sparsebody/nn/storage.hpp"
#ifdef SPARSEBODY_BENCH_TORCH
#include "torch_peer.hpp"
#endif

using namespace sparsebody;
using sparsebody_test::add_gru;
using sparsebody_test::add_linear;

namespace {

inline constexpr char kGru[] = "gru";
template <int H>
using GruOnly = nn::Named<kGru, nn::GRU<float, 37, H>>;
constexpr int kLatent = 256;  // the core issue's benchmark shape: Linear(H->256)+ReLU -> heads
template <int H>
using LoBSTr = networks::LoBSTrNet<float, H, kLatent>;
template <int H>
using GruOnlyF16 = nn::Named<kGru, nn::GRU<float, 37, H, 1, nn::f16>>;
template <int H>
using LoBSTrF16 = networks::LoBSTrNet<float, H, kLatent, 37, nn::f16>;
using Gsig = networks::N3PPredictorNet<float, 45, 64, 12>;
using Glo = networks::N3PPredictorNet<float, 12, 128, 113>;
using Gup = networks::N3PPredictorNet<float, 45, 128, 201>;
using N3PPolicy = networks::N3PPolicyNet<float, 868, 72>;
using QuestSim = networks::QuestSimPolicyNet<float, 475, 33>;
using N3PPolicyF16 = networks::N3PPolicyNet<float, 868, 72, 256, nn::f16>;
using QuestSimF16 = networks::QuestSimPolicyNet<float, 475, 33, nn::f16>;
using GsigF16 = networks::N3PPredictorNet<float, 45, 64, 12, 3, nn::f16>;
using GloF16 = networks::N3PPredictorNet<float, 12, 128, 113, 3, nn::f16>;
using GupF16 = networks::N3PPredictorNet<float, 45, 128, 201, 3, nn::f16>;
template <int H>
using LoBSTrF16Small = networks::LoBSTrNet<float, H, kLatent, 37, nn::f16>;
// int8 weight storage (nn/int8.hpp): a quarter of the float bytes, dynamic input quantization.
template <int H>
using GruOnlyQ8 = nn::Named<kGru, nn::GRU<float, 37, H, 1, nn::q8>>;
template <int H>
using LoBSTrQ8 = networks::LoBSTrNet<float, H, kLatent, 37, nn::q8>;
using GsigQ8 = networks::N3PPredictorNet<float, 45, 64, 12, 3, nn::q8>;
using GloQ8 = networks::N3PPredictorNet<float, 12, 128, 113, 3, nn::q8>;
using GupQ8 = networks::N3PPredictorNet<float, 45, 128, 201, 3, nn::q8>;
using N3PPolicyQ8 = networks::N3PPolicyNet<float, 868, 72, 256, nn::q8>;
using QuestSimQ8 = networks::QuestSimPolicyNet<float, 475, 33, nn::q8>;

io::TensorTable lobstr_table(int H, int latent, bool gru_only = false) {
  return sparsebody_test::random_lobstr_table(H, latent, 1, gru_only);
}
io::TensorTable n3p_table(int in, int H, int out) {
  std::mt19937 rng(2);
  io::TensorTable t("random");
  add_linear(t, "encoder.", in, H, rng);
  add_gru(t, "gru.", H, H, 3, rng);
  add_linear(t, "decoder.", H, out, rng);
  return t;
}
io::TensorTable mlp_table(std::vector<int> sizes) {
  std::mt19937 rng(3);
  io::TensorTable t("random");
  for (std::size_t i = 0; i + 1 < sizes.size(); ++i)
    add_linear(t, "layers." + std::to_string(i) + ".", sizes[i], sizes[i + 1], rng, 0.05);
  return t;
}
// Multiply-adds of one step: the entries of the weight matrices (biases are adds only).
std::int64_t step_macs(const io::TensorTable& t) {
  std::int64_t n = 0;
  for (const auto& kv : t.tensors())
    if (kv.second.shape.size() == 2) n += kv.second.shape[0] * kv.second.shape[1];
  return n;
}
// The least time N steps can take at this build's arithmetic limit (compute_limit.hpp): int8
// products for q8 storage, float FMAs otherwise (f16 widens to float before its FMAs).
void bench_limit(benchmark::State& st, const io::TensorTable& table, const char* name) {
  const std::int64_t macs = st.range(0) * step_macs(table);
  if (std::string(name).find("_q8") != std::string::npos)
    sparsebody_bench::bench_compute_limit<true>(st, macs);
  else
    sparsebody_bench::bench_compute_limit<false>(st, macs);
}
std::size_t parameter_bytes(const io::TensorTable& t) {
  std::size_t n = 0;
  for (const auto& kv : t.tensors()) n += kv.second.values.size() * sizeof(float);
  return n;
}

template <class Net>
std::shared_ptr<const nn::NetworkWeights<Net>> make_weights(io::TensorTable t, const char* kind) {
  return sparsebody_test::weights_from_table<Net>(std::move(t), kind);
}

template <class Net>
void bench_network(benchmark::State& st, io::TensorTable table, const char* kind) {
  const std::size_t param_bytes = parameter_bytes(table);
  auto w = make_weights<Net>(std::move(table), kind);
  nn::Network<Net> net(w);
  std::vector<float> x(Net::in_size);
  std::mt19937 rng(4);
  std::normal_distribution<float> d(0, 1);
  for (auto& v : x) v = d(rng);
  for (auto _ : st) {
    const float* y = net.step(x.data());
    benchmark::DoNotOptimize(y);
    benchmark::ClobberMemory();
  }
  st.counters["weight_bytes"] = double(w->bytes());
  st.counters["param_bytes"] = double(param_bytes);
  st.counters["GB/s"] = benchmark::Counter(double(w->bytes()), benchmark::Counter::kIsIterationInvariantRate,
                                           benchmark::Counter::OneK::kIs1000);
}

// Plain read of n floats' worth of bytes at p with aligned SIMD loads into 8 independent
// accumulators (p is cache-line aligned, as every weight buffer is). Bitwise OR, not addition: the
// buffers of f16 / int8 storage read as floats may hold NaN or denormal patterns.
inline float plain_read(const float* p, std::size_t n) {
  using B = nn::Batch<float>;
  constexpr std::size_t L = nn::kLanes<float>;
  B acc[8] = {B(0.f), B(0.f), B(0.f), B(0.f), B(0.f), B(0.f), B(0.f), B(0.f)};
  std::size_t i = 0;
  for (; i + 8 * L <= n; i += 8 * L)
    for (int k = 0; k < 8; ++k) acc[k] = acc[k] | B::load_aligned(p + i + k * L);
  for (; i + L <= n; i += L) acc[0] = acc[0] | B::load_aligned(p + i);
  for (int k = 1; k < 8; ++k) acc[0] = acc[0] | acc[k];
  alignas(64) float lanes[L];
  acc[0].store_aligned(lanes);
  std::uint32_t bits = 0, b = 0;
  for (std::size_t k = 0; k < L; ++k) std::memcpy(&b, &lanes[k], 4), bits |= b;
  for (; i < n; ++i) std::memcpy(&b, p + i, 4), bits |= b;  // none: buffers are whole cache lines
  float s;
  std::memcpy(&s, &bits, 4);
  return s;
}

// The floor: stream `bytes` of float weights with plain_read (the same reader as paired/).
void BM_WeightRead(benchmark::State& st) {
  const std::size_t n = static_cast<std::size_t>(st.range(0)) / sizeof(float);
  AlignedBuffer<float> buf(n);
  for (std::size_t i = 0; i < n; ++i) buf[i] = float(i % 7) * 0.25f;
  for (auto _ : st) benchmark::DoNotOptimize(plain_read(buf.data(), n));
  st.counters["GB/s"] = benchmark::Counter(double(n * sizeof(float)), benchmark::Counter::kIsIterationInvariantRate,
                                           benchmark::Counter::OneK::kIs1000);
}

// The ratio "step / plain read of its weights", measured robustly on a noisy shared machine: every
// iteration times one network step and then one plain read of the network's *own* weight buffers
// (the same bytes at the same addresses, so both see the same cache state), and the counters are
// the medians of the per-iteration times. Separate benchmarks of the two drift apart by up to 20 %
// here when the shared L3 / memory bandwidth changes between them.
template <class Net>
void bench_paired(benchmark::State& st, io::TensorTable table, const char* kind) {
  using Clock = std::chrono::steady_clock;
  auto w = make_weights<Net>(std::move(table), kind);
  nn::Network<Net> net(w);
  std::vector<std::pair<const float*, std::size_t>> bufs;
  w->store().for_each_buffer([&](const void* p, std::size_t bytes) {
    bufs.emplace_back(static_cast<const float*>(p), bytes / sizeof(float));
  });
  std::vector<float> x(Net::in_size);
  std::mt19937 rng(4);
  std::normal_distribution<float> d(0, 1);
  for (auto& v : x) v = d(rng);
  constexpr std::size_t kMaxSamples = 1 << 18;
  std::vector<double> t_step, t_read;
  t_step.reserve(kMaxSamples);
  t_read.reserve(kMaxSamples);
  for (auto _ : st) {
    const auto a = Clock::now();
    const float* y = net.step(x.data());
    benchmark::DoNotOptimize(y);
    benchmark::ClobberMemory();
    const auto b = Clock::now();
    float s = 0;
    for (const auto& [p, n] : bufs) s += plain_read(p, n);
    benchmark::DoNotOptimize(s);
    const auto c = Clock::now();
    if (t_step.size() < kMaxSamples) {
      t_step.push_back(std::chrono::duration<double, std::micro>(b - a).count());
      t_read.push_back(std::chrono::duration<double, std::micro>(c - b).count());
    }
  }
  auto median = [](std::vector<double>& v) {
    if (v.empty()) return 0.0;
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  const double ms = median(t_step), mr = median(t_read);
  st.counters["step_us"] = ms;
  st.counters["read_us"] = mr;
  st.counters["step/read"] = mr > 0 ? ms / mr : 0;
  st.counters["weight_bytes"] = double(w->bytes());
}

// N instances sharing one weight set: one NetworkBatch step (each weight streamed once for all N)
// against N separate Network steps, same inputs. Counter us/instance: time per instance.
template <class Net>
std::vector<std::vector<float>> batch_inputs(int n) {
  std::mt19937 rng(5);
  std::normal_distribution<float> d(0, 1);
  std::vector<std::vector<float>> x(n, std::vector<float>(Net::in_size));
  for (auto& v : x)
    for (auto& e : v) e = d(rng);
  return x;
}
template <class Net>
void bench_batch(benchmark::State& st, io::TensorTable table, const char* kind) {
  const int n = static_cast<int>(st.range(0));
  auto w = make_weights<Net>(std::move(table), kind);
  nn::NetworkBatch<Net> batch(w, n);
  const auto x = batch_inputs<Net>(n);
  std::vector<const float*> xp;
  for (const auto& v : x) xp.push_back(v.data());
  for (auto _ : st) {
    batch.step(xp.data());
    benchmark::DoNotOptimize(batch.output(n - 1));
    benchmark::ClobberMemory();
  }
  st.counters["us/instance"] = benchmark::Counter(double(n) * 1e-6, benchmark::Counter::kIsIterationInvariantRate |
                                                                       benchmark::Counter::kInvert);
}
template <class Net>
void bench_singles(benchmark::State& st, io::TensorTable table, const char* kind) {
  const int n = static_cast<int>(st.range(0));
  auto w = make_weights<Net>(std::move(table), kind);
  std::vector<nn::Network<Net>> nets;
  for (int i = 0; i < n; ++i) nets.emplace_back(w);
  const auto x = batch_inputs<Net>(n);
  for (auto _ : st) {
    for (int i = 0; i < n; ++i) benchmark::DoNotOptimize(nets[i].step(x[i].data()));
    benchmark::ClobberMemory();
  }
  st.counters["us/instance"] = benchmark::Counter(double(n) * 1e-6, benchmark::Counter::kIsIterationInvariantRate |
                                                                       benchmark::Counter::kInvert);
}

// One q8 product shape, 16 instances: detail::gemv_batch_q8_upgrade (groups of instances share each
// weight load) against 16 single products, with upgrade u (none: the build's kernel). Rows
// "q8_group/<kernel>/<rows>x<cols>/{batch,singles}": how much the grouping of nn/int8.hpp pays for
// each kernel the CPU runs, on the products of the paper networks.
void bench_q8_group(benchmark::State& st, nn::detail::Q8Upgrade u, int rows, int cols, bool batch) {
  constexpr int n = 16;
  std::mt19937 rng(9);
  std::normal_distribution<float> d(0, 1);
  std::vector<float> dense(static_cast<std::size_t>(rows) * cols);
  for (float& v : dense) v = d(rng);
  const sparsebody_test::PackedQ8 packed(dense, rows, cols);
  const nn::PanelMatrix<float, nn::q8>& W = packed.m;
  std::vector<std::vector<float>> x(n, std::vector<float>(cols)), y(n, std::vector<float>(nn::padded<float>(rows)));
  std::vector<const float*> xp;
  std::vector<float*> yp;
  for (int i = 0; i < n; ++i) {
    for (float& v : x[i]) v = d(rng);
    xp.push_back(x[i].data());
    yp.push_back(y[i].data());
  }
  for (auto _ : st) {
    if (batch)
      nn::detail::gemv_batch_q8_upgrade(u, W, n, xp.data(), nullptr, yp.data());
    else
      for (int i = 0; i < n; ++i) nn::detail::gemv_q8_upgrade(u, W, xp[i], nullptr, yp[i]);
    benchmark::ClobberMemory();
  }
  st.counters["GMAC/s"] = benchmark::Counter(double(n) * rows * cols * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
}

// Loading the paper-size LoBSTr model (37->1024 GRU, 13 MB of float32) from weights JSON text.
void BM_LoadLoBSTr1024(benchmark::State& st) {
  const bool base64 = st.range(0) == 1;
  io::TensorTable t = lobstr_table(1024, 128);
  nlohmann::json j = {{"format", "sparsebody-weights"}, {"version", 1}, {"kind", "lobstr"},
                      {"meta", {{"input_size", 37}, {"output_size", 52}}}};
  for (const auto& kv : t.tensors()) {
    nlohmann::json tj = {{"shape", kv.second.shape}};
    if (base64) {
      std::vector<float> f(kv.second.values.begin(), kv.second.values.end());
      tj["dtype"] = "float32";
      tj["data"] = io::base64_encode(reinterpret_cast<const std::uint8_t*>(f.data()), f.size() * 4);
    } else {
      tj["data"] = kv.second.values;
    }
    j["tensors"][kv.first] = tj;
  }
  const std::string text = j.dump();
  for (auto _ : st) {
    auto w = nn::NetworkWeights<networks::LoBSTrNet<float, 1024, 128>>::from_string(text, "lobstr", "bench");
    benchmark::DoNotOptimize(w.get());
  }
  st.counters["json_MB"] = double(text.size()) / 1e6;
}

#ifdef SPARSEBODY_BENCH_TORCH
void bench_torch(benchmark::State& st, std::unique_ptr<sparsebody_bench::TorchPeer> p) {
  for (auto _ : st) p->step();
}
#endif

struct Entry {
  std::string name;
  std::size_t weight_bytes;  // what sparsebody streams per step (padded), for the matching read
};

void register_all() {
  using sparsebody_bench::add_ratio;
  auto reg = [](const std::string& name, auto fn) { benchmark::RegisterBenchmark(name.c_str(), fn)->Unit(benchmark::kMicrosecond); };
  auto bytes_of = [](auto w) { return w->bytes(); };
  std::vector<Entry> entries;
  // Each network: its step alone, and (paired/) its step interleaved with a plain read of its own
  // weight buffers (see bench_paired: the robust step/read ratio).
#define SB_NET(NAME, NET, TABLE, KIND)                                                           \
  reg("sparsebody/" NAME, [](benchmark::State& s) { bench_network<NET>(s, TABLE, KIND); });      \
  reg("paired/" NAME, [](benchmark::State& s) { bench_paired<NET>(s, TABLE, KIND); });           \
  entries.push_back({NAME, bytes_of(make_weights<NET>(TABLE, KIND))});
  SB_NET("GRU_37x1024", GruOnly<1024>, lobstr_table(1024, 0, true), "gru")
  SB_NET("GRU_37x256", GruOnly<256>, lobstr_table(256, 0, true), "gru")
  SB_NET("LoBSTr_H1024", LoBSTr<1024>, lobstr_table(1024, kLatent), "lobstr")
  SB_NET("LoBSTr_H256", LoBSTr<256>, lobstr_table(256, kLatent), "lobstr")
  SB_NET("GRU_37x1024_f16weights", GruOnlyF16<1024>, lobstr_table(1024, 0, true), "gru")
  SB_NET("GRU_37x256_f16weights", GruOnlyF16<256>, lobstr_table(256, 0, true), "gru")
  SB_NET("LoBSTr_H1024_f16weights", LoBSTrF16<1024>, lobstr_table(1024, kLatent), "lobstr")
  SB_NET("N3P_Gsig_H64", Gsig, n3p_table(45, 64, 12), "n3p_signal")
  SB_NET("N3P_Glo_H128", Glo, n3p_table(12, 128, 113), "n3p_lower")
  SB_NET("N3P_Gup_H128", Gup, n3p_table(45, 128, 201), "n3p_upper")
  SB_NET("N3P_policy_868_256_256_72", N3PPolicy, mlp_table({868, 256, 256, 72}), "n3p_policy")
  SB_NET("QuestSim_475_400_300_200_33", QuestSim, mlp_table({475, 400, 300, 200, 33}), "questsim_policy")
  SB_NET("LoBSTr_H256_f16weights", LoBSTrF16Small<256>, lobstr_table(256, kLatent), "lobstr")
  SB_NET("N3P_Gsig_H64_f16weights", GsigF16, n3p_table(45, 64, 12), "n3p_signal")
  SB_NET("N3P_Glo_H128_f16weights", GloF16, n3p_table(12, 128, 113), "n3p_lower")
  SB_NET("N3P_Gup_H128_f16weights", GupF16, n3p_table(45, 128, 201), "n3p_upper")
  SB_NET("N3P_policy_868_256_256_72_f16weights", N3PPolicyF16, mlp_table({868, 256, 256, 72}), "n3p_policy")
  SB_NET("QuestSim_475_400_300_200_33_f16weights", QuestSimF16, mlp_table({475, 400, 300, 200, 33}), "questsim_policy")
  SB_NET("GRU_37x1024_q8weights", GruOnlyQ8<1024>, lobstr_table(1024, 0, true), "gru")
  SB_NET("GRU_37x256_q8weights", GruOnlyQ8<256>, lobstr_table(256, 0, true), "gru")
  SB_NET("LoBSTr_H1024_q8weights", LoBSTrQ8<1024>, lobstr_table(1024, kLatent), "lobstr")
  SB_NET("LoBSTr_H256_q8weights", LoBSTrQ8<256>, lobstr_table(256, kLatent), "lobstr")
  SB_NET("N3P_Gsig_H64_q8weights", GsigQ8, n3p_table(45, 64, 12), "n3p_signal")
  SB_NET("N3P_Glo_H128_q8weights", GloQ8, n3p_table(12, 128, 113), "n3p_lower")
  SB_NET("N3P_Gup_H128_q8weights", GupQ8, n3p_table(45, 128, 201), "n3p_upper")
  SB_NET("N3P_policy_868_256_256_72_q8weights", N3PPolicyQ8, mlp_table({868, 256, 256, 72}), "n3p_policy")
  SB_NET("QuestSim_475_400_300_200_33_q8weights", QuestSimQ8, mlp_table({475, 400, 300, 200, 33}), "questsim_policy")
#undef SB_NET
  // Batched steps (nn/batch.hpp) at N = 1, 4, 16, 64 against N single steps, same run.
#define SB_BATCH(NAME, NET, TABLE, KIND)                                                                           \
  for (int n : {1, 4, 16, 64}) {                                                                                  \
    benchmark::RegisterBenchmark("batch/" NAME, [](benchmark::State& s) { bench_batch<NET>(s, TABLE, KIND); })     \
        ->Arg(n)->Unit(benchmark::kMicrosecond);                                                                  \
    benchmark::RegisterBenchmark("singles/" NAME, [](benchmark::State& s) { bench_singles<NET>(s, TABLE, KIND); }) \
        ->Arg(n)->Unit(benchmark::kMicrosecond);                                                                  \
    add_ratio(std::string("batch / singles ") + NAME + " N=" + std::to_string(n),                                 \
              std::string("batch/") + NAME + "/" + std::to_string(n), std::string("singles/") + NAME + "/" + std::to_string(n)); \
    benchmark::RegisterBenchmark("limit/" NAME, [](benchmark::State& s) { bench_limit(s, TABLE, NAME); })          \
        ->Arg(n)->Unit(benchmark::kMicrosecond);                                                                  \
    add_ratio(std::string("batch / arithmetic limit ") + NAME + " N=" + std::to_string(n),                        \
              std::string("batch/") + NAME + "/" + std::to_string(n), std::string("limit/") + NAME + "/" + std::to_string(n)); \
  }                                                                                                               \
  add_ratio(std::string("arithmetic limit N=16 / one step ") + NAME + " (16 in <= 4x one needs <= 4)",              \
            std::string("limit/") + NAME + "/16", std::string("batch/") + NAME + "/1");
  SB_BATCH("GRU_37x1024", GruOnly<1024>, lobstr_table(1024, 0, true), "gru")
  SB_BATCH("GRU_37x256", GruOnly<256>, lobstr_table(256, 0, true), "gru")
  SB_BATCH("QuestSim_475_400_300_200_33", QuestSim, mlp_table({475, 400, 300, 200, 33}), "questsim_policy")
  SB_BATCH("QuestSim_475_400_300_200_33_f16weights", QuestSimF16, mlp_table({475, 400, 300, 200, 33}), "questsim_policy")
  SB_BATCH("GRU_37x256_q8weights", GruOnlyQ8<256>, lobstr_table(256, 0, true), "gru")
  SB_BATCH("LoBSTr_H256", LoBSTr<256>, lobstr_table(256, kLatent), "lobstr")
  SB_BATCH("LoBSTr_H256_q8weights", LoBSTrQ8<256>, lobstr_table(256, kLatent), "lobstr")
  SB_BATCH("N3P_Gup_H128", Gup, n3p_table(45, 128, 201), "n3p_upper")
  SB_BATCH("N3P_Gup_H128_q8weights", GupQ8, n3p_table(45, 128, 201), "n3p_upper")
  SB_BATCH("QuestSim_475_400_300_200_33_q8weights", QuestSimQ8, mlp_table({475, 400, 300, 200, 33}), "questsim_policy")
#undef SB_BATCH
  // Grouping of q8 batches per kernel this CPU runs (the build's, and each run-time upgrade it has):
  // the gate products of the LoBSTr / GRU 256 and N3P Gup hidden layers and QuestSim's first layer.
  {
    using nn::detail::Q8Upgrade;
    std::vector<std::pair<Q8Upgrade, std::string>> kernels{{Q8Upgrade::none, "build"}};
    for (Q8Upgrade u : nn::detail::kQ8UpgradeOrder)
      if (nn::detail::q8_cpu_has(u)) kernels.emplace_back(u, nn::detail::q8_upgrade_id(u));
    for (const auto& [u, kname] : kernels)
      for (const auto& [rows, cols] : {std::pair{768, 256}, std::pair{384, 128}, std::pair{400, 475}}) {
        const std::string base = "q8_group/" + kname + "/" + std::to_string(rows) + "x" + std::to_string(cols);
        for (bool b : {true, false}) {
          const Q8Upgrade uu = u;
          const int r = rows, c = cols;
          benchmark::RegisterBenchmark((base + (b ? "/batch" : "/singles")).c_str(),
                                       [uu, r, c, b](benchmark::State& s) { bench_q8_group(s, uu, r, c, b); })
              ->Unit(benchmark::kMicrosecond);
        }
        add_ratio("q8 16 singles / grouped batch " + base.substr(9), base + "/singles", base + "/batch");
      }
  }
  // The most int8 can gain over float where both are bound by arithmetic (weights in L1/L2): the
  // same 1 M multiply-adds as float FMAs and as the q8 kernel's int8 instructions.
  for (int i8 = 0; i8 < 2; ++i8)
    benchmark::RegisterBenchmark(i8 ? "limit/int8_1M" : "limit/f32_1M", [i8](benchmark::State& s) {
      if (i8) sparsebody_bench::bench_compute_limit<true>(s, 1 << 20);
      else sparsebody_bench::bench_compute_limit<false>(s, 1 << 20);
    })->Unit(benchmark::kMicrosecond);
  add_ratio("arithmetic limit f32 / int8, 1 M multiply-adds (the compute-bound q8 speed-up ceiling)", "limit/f32_1M",
            "limit/int8_1M");
  // Storage speed-ups, same run: float time / f16 time and float time / q8 time (> 1: faster).
  for (const char* n : {"GRU_37x1024", "GRU_37x256", "LoBSTr_H1024", "LoBSTr_H256", "N3P_Gsig_H64", "N3P_Glo_H128",
                        "N3P_Gup_H128", "N3P_policy_868_256_256_72", "QuestSim_475_400_300_200_33"}) {
    add_ratio(std::string("speed-up f16 ") + n + " (float / f16)", std::string("sparsebody/") + n,
              std::string("sparsebody/") + n + "_f16weights");
    add_ratio(std::string("speed-up q8  ") + n + " (float / q8)", std::string("sparsebody/") + n,
              std::string("sparsebody/") + n + "_q8weights");
  }
  add_ratio("GRU_37x1024 f16 weights / plain read of its float weights", "sparsebody/GRU_37x1024_f16weights",
            "read/" + std::to_string(entries[0].weight_bytes) + "B/" + std::to_string(entries[0].weight_bytes));
  add_ratio("LoBSTr_H1024 f16 weights / plain read of its float weights", "sparsebody/LoBSTr_H1024_f16weights",
            "read/" + std::to_string(entries[2].weight_bytes) + "B/" + std::to_string(entries[2].weight_bytes));
  add_ratio("LoBSTr_H1024 f16 weights sparsebody / LibTorch float", "sparsebody/LoBSTr_H1024_f16weights",
            "libtorch/LoBSTr_H1024");
  for (const Entry& e : entries) {
    const std::string read = "read/" + std::to_string(e.weight_bytes) + "B";
    benchmark::RegisterBenchmark(read.c_str(), BM_WeightRead)->Arg(static_cast<int64_t>(e.weight_bytes))->Unit(benchmark::kMicrosecond);
    add_ratio(e.name + " / plain read of its weights", "sparsebody/" + e.name,
              read + "/" + std::to_string(e.weight_bytes));
  }
#ifdef SPARSEBODY_BENCH_TORCH
  using namespace sparsebody_bench;
  torch_init_single_thread();
  reg("libtorch/GRU_37x1024", [](benchmark::State& s) { bench_torch(s, torch_lobstr(1024, kLatent)); });
  reg("libtorch/LoBSTr_H1024", [](benchmark::State& s) { bench_torch(s, torch_lobstr(1024, kLatent)); });
  reg("libtorch/LoBSTr_H256", [](benchmark::State& s) { bench_torch(s, torch_lobstr(256, kLatent)); });
  reg("libtorch/N3P_Gsig_H64", [](benchmark::State& s) { bench_torch(s, torch_n3p_predictor(45, 64, 12)); });
  reg("libtorch/N3P_Glo_H128", [](benchmark::State& s) { bench_torch(s, torch_n3p_predictor(12, 128, 113)); });
  reg("libtorch/N3P_Gup_H128", [](benchmark::State& s) { bench_torch(s, torch_n3p_predictor(45, 128, 201)); });
  reg("libtorch/N3P_policy_868_256_256_72", [](benchmark::State& s) { bench_torch(s, torch_mlp({868, 256, 256, 72}, false)); });
  reg("libtorch/QuestSim_475_400_300_200_33", [](benchmark::State& s) { bench_torch(s, torch_mlp({475, 400, 300, 200, 33}, true)); });
  for (const char* n : {"LoBSTr_H256", "N3P_policy_868_256_256_72", "QuestSim_475_400_300_200_33"})
    add_ratio(std::string(n) + " f16 weights sparsebody / LibTorch float", std::string("sparsebody/") + n + "_f16weights",
              std::string("libtorch/") + n);
  for (const char* n : {"LoBSTr_H1024", "LoBSTr_H256", "N3P_Gsig_H64", "N3P_Glo_H128", "N3P_Gup_H128",
                        "N3P_policy_868_256_256_72", "QuestSim_475_400_300_200_33"}) {
    add_ratio(std::string(n) + " sparsebody / LibTorch", std::string("sparsebody/") + n, std::string("libtorch/") + n);
    add_ratio(std::string(n) + " q8 weights sparsebody / LibTorch float", std::string("sparsebody/") + n + "_q8weights",
              std::string("libtorch/") + n);
  }
#endif
  benchmark::RegisterBenchmark("load/LoBSTr_H1024_json_list", BM_LoadLoBSTr1024)->Arg(0)->Unit(benchmark::kMillisecond)->Iterations(3);
  benchmark::RegisterBenchmark("load/LoBSTr_H1024_json_base64", BM_LoadLoBSTr1024)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(5);
}

}  // namespace

// The CPU and what this build compiled for, printed beside the figures.
void print_target() {
  std::ifstream f("/proc/cpuinfo");
  std::string line, model = "unknown CPU", family;
  while (std::getline(f, line)) {
    if (line.rfind("model name", 0) == 0 && model == "unknown CPU") model = line.substr(line.find(':') + 2);
    if (line.rfind("cpu family", 0) == 0 && family.empty()) family = line.substr(line.find(':') + 2);
  }
  const nn::StorageChoice c = nn::fastest_storage();
  std::printf("CPU: %s (family %s); build: %d float lanes, int8 kernel %s (SPARSEBODY_Q8_RUNTIME=off: the build's own), f16 widening %s; storage auto -> %s\n",
              model.c_str(), family.c_str(), nn::kLanes<float>, nn::q8_kernel_in_use(),
              nn::kF16Hardware ? "in hardware" : "portable", nn::storage_name(c.storage));
}

int main(int argc, char** argv) {
  print_target();
  register_all();
  return sparsebody_bench::run_with_ratios(argc, argv, "sparsebody networks");
}
