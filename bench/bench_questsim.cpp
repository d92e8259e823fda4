// QuestSim control step and its parts, on the default avatar scaled to 1.62 m:
//   BM_QuestSimControlStep<float/double simulation, float/f16/q8 policy weights>: observation + policy + torques
//     + 2 substeps + fall check (QuestSimPipeline::control_step), the issue's <= 40 us target;
//   BM_QuestSimTick: the same from a TrackerFrame (sanitiser + window shift added);
//   BM_QuestSimObservation, BM_QuestSimPolicy<W>, BM_QuestSimSubstep: the parts;
//   BM_QuestSimSession<W>: avatar::QuestSimSession (calibration, output pose) with the shipped trained
//     policy, per 36 Hz tick: two 72 Hz frames of a user standing and gesturing (falls counted).
// The policy has random weights made here (PyTorch-default uniform init, output layer x 0.01 like a
// PPO policy head, foot forces normalised by 618 N): an untrained policy, so the character falls
// about every 10 steps and is stood up again inside control_step (counted as `falls`), as it would be
// at run time. Feet are on the ground in every step (contacts: `contacts` counter).
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <string>

#include <nlohmann/json.hpp>

#include "sparsebody/avatar/questsim.hpp"
#include "sparsebody/avatar/questsim_session.hpp"

using namespace sparsebody;
using namespace sparsebody::control;
using namespace sparsebody::avatar;

namespace {

constexpr double kHeight = 1.62;

// The weights document of a random QuestSim policy (list-encoded tensors).
std::string random_policy_json(int in, int out, unsigned seed = 7) {
  std::mt19937 rng(seed);
  nlohmann::json doc;
  doc["format"] = "sparsebody-weights";
  doc["version"] = 1;
  doc["kind"] = networks::kQuestSimPolicyKind;
  doc["meta"] = {{"input_size", in}, {"output_size", out}, {"frame_rate", 36}, {"random_weights", true}};
  const int sizes[] = {in, 400, 300, 200, out};
  for (int l = 0; l < 4; ++l) {
    const double bound = 1.0 / std::sqrt(double(sizes[l])) * (l == 3 ? 0.01 : 1.0);
    std::uniform_real_distribution<double> u(-bound, bound);
    std::vector<double> w(std::size_t(sizes[l + 1]) * sizes[l]), b(sizes[l + 1]);
    for (auto& x : w) x = u(rng);
    for (auto& x : b) x = u(rng);
    doc["tensors"]["layers." + std::to_string(l) + ".weight"] = {{"shape", {sizes[l + 1], sizes[l]}}, {"data", w}};
    doc["tensors"]["layers." + std::to_string(l) + ".bias"] = {{"shape", {sizes[l + 1]}}, {"data", b}};
  }
  using L = QuestSimLayout<character::kDefaultAvatarBodies, character::kDefaultAvatarJointDofs, 6>;
  std::vector<double> mean(in, 0.0), stdv(in, 1.0);
  for (int k = 0; k < 6; ++k) stdv[L::f + k] = 618.0;
  doc["normalization"]["input_mean"] = {{"shape", {in}}, {"data", mean}};
  doc["normalization"]["input_std"] = {{"shape", {in}}, {"data", stdv}};
  return doc.dump();
}

template <class C>
std::shared_ptr<const typename C::Weights> weights() {
  static auto w = C::Weights::from_string(random_policy_json(C::kObservationSize, C::kActionSize),
                                          networks::kQuestSimPolicyKind, "random questsim policy");
  return w;
}

// A user standing at the origin facing -Z, arms slightly moving.
trackers::TrackerFrame user_frame(double t) {
  trackers::TrackerFrame f;
  f.time = t;
  const Eigen::Vector3d head(0.02 * std::sin(t), 0.936 * kHeight, 0.0);
  f.pose[0] = {trackers::to_xr(Eigen::Quaterniond::Identity()), trackers::to_xr(head)};
  for (int s = 0; s < 2; ++s) {
    const Eigen::Vector3d hand = head + Eigen::Vector3d(s == 0 ? -0.25 : 0.25, -0.5 + 0.1 * std::sin(2 * t + s), -0.25);
    f.pose[1 + s] = {trackers::to_xr(Eigen::Quaterniond::Identity()), trackers::to_xr(hand)};
  }
  f.valid = {true, true, true, false};
  return f;
}

template <class C>
void warm_up(C& c) {
  for (int k = 0; k < 7; ++k) c.tick(user_frame(k / 36.0));
}

template <class C>
void report(benchmark::State& st, const C& c, long long falls0) {
  st.counters["falls"] = benchmark::Counter(double(c.falls() - falls0), benchmark::Counter::kAvgIterations);
  st.counters["failures"] = double(c.simulation_failures());
  st.counters["contacts"] = c.simulator().num_contacts();
}

template <class S, class W>
void BM_QuestSimControlStep(benchmark::State& st) {
  using C = QuestSimPipeline<S, W>;
  C c(weights<C>(), kHeight);
  warm_up(c);
  const long long f0 = c.falls();
  for (auto _ : st) benchmark::DoNotOptimize(c.control_step());
  report(st, c, f0);
}

template <class S, class W>
void BM_QuestSimTick(benchmark::State& st) {
  using C = QuestSimPipeline<S, W>;
  C c(weights<C>(), kHeight);
  warm_up(c);
  const long long f0 = c.falls();
  int k = 7;
  trackers::TrackerFrame frames[64];
  for (int i = 0; i < 64; ++i) frames[i] = user_frame(i / 36.0);
  for (auto _ : st) {
    trackers::TrackerFrame& f = frames[k & 63];
    f.time = k++ / 36.0;
    benchmark::DoNotOptimize(c.tick(f));
  }
  report(st, c, f0);
}

template <class S>
void BM_QuestSimObservation(benchmark::State& st) {
  using C = QuestSimPipeline<S>;
  C c(weights<C>(), kHeight);
  warm_up(c);
  alignas(64) std::array<float, C::kObservationSize> o{};
  for (auto _ : st) {
    c.observation_builder().build(c.simulator(), c.window(), S(kHeight), o.data());
    benchmark::DoNotOptimize(o.data());
    benchmark::ClobberMemory();
  }
}

template <class W>
void BM_QuestSimPolicy(benchmark::State& st) {
  using C = QuestSimPipeline<float, W>;
  C c(weights<C>(), kHeight);
  warm_up(c);
  nn::Network<typename C::Net> net(weights<C>());
  const auto x = c.observation();
  for (auto _ : st) benchmark::DoNotOptimize(net.step(x.data()));
  st.counters["weight_bytes"] = double(net.weights().bytes());
}

// One 1/72 s substep in torque mode with the policy's torques of a standing frame; the state is
// reset to standing every range(0) substeps: 30 lets the unbalanced character sag and slide (more
// active-set passes, as under the random policy), 1 times the first substep from rest every time
// (closer to a character that keeps its balance). `aba_passes` = ABA solves per substep.
template <class S>
void BM_QuestSimSubstep(benchmark::State& st) {
  const int period = int(st.range(0));
  using C = QuestSimPipeline<S>;
  C c(weights<C>(), kHeight);
  warm_up(c);
  auto& sim = c.simulator();
  const auto q0 = sim.q();
  const auto v0 = sim.v();
  const auto tau = c.torques();
  int k = 0;
  long long passes = 0, contacts = 0, n = 0;
  for (auto _ : st) {
    sim.torques() = tau;
    benchmark::DoNotOptimize(sim.step(S(1.0 / 72)));
    passes += sim.last_passes();
    contacts += sim.num_contacts();
    ++n;
    if (++k == period) { k = 0; sim.set_state(q0, v0); }
  }
  st.counters["contacts"] = double(contacts) / double(n);
  st.counters["aba_passes"] = double(passes) / double(n);
}

template <class W>
void BM_QuestSimSession(benchmark::State& st) {
  using Session = QuestSimSession<float, W>;
  static auto w = Session::load(SPARSEBODY_QUESTSIM_SHIPPED_POLICY);
  Session s(w);
  int k = 0;
  for (; k < 144; ++k) s.push(user_frame(k / 72.0));  // calibrated (the user stands), sized
  const long long f0 = s.falls(), r0 = s.restarts();
  long long ticks = 0;
  for (auto _ : st) {
    ticks += s.push(user_frame(k++ / 72.0));
    ticks += s.push(user_frame(k++ / 72.0));
    benchmark::DoNotOptimize(s.world().position.data());
  }
  st.counters["ticks"] = benchmark::Counter(double(ticks), benchmark::Counter::kAvgIterations);
  st.counters["falls"] = double(s.falls() - f0);
  st.counters["restarts"] = double(s.restarts() - r0);
  st.counters["stature"] = s.calibration_report().stature;
}

}  // namespace

BENCHMARK_TEMPLATE(BM_QuestSimSession, float);
BENCHMARK_TEMPLATE(BM_QuestSimSession, nn::f16);
BENCHMARK_TEMPLATE(BM_QuestSimSession, nn::q8);
BENCHMARK_TEMPLATE(BM_QuestSimControlStep, float, float);
BENCHMARK_TEMPLATE(BM_QuestSimControlStep, float, nn::f16);
BENCHMARK_TEMPLATE(BM_QuestSimControlStep, float, nn::q8);
BENCHMARK_TEMPLATE(BM_QuestSimControlStep, double, float);
BENCHMARK_TEMPLATE(BM_QuestSimTick, float, float);
BENCHMARK_TEMPLATE(BM_QuestSimObservation, float);
BENCHMARK_TEMPLATE(BM_QuestSimObservation, double);
BENCHMARK_TEMPLATE(BM_QuestSimPolicy, float);
BENCHMARK_TEMPLATE(BM_QuestSimPolicy, nn::f16);
BENCHMARK_TEMPLATE(BM_QuestSimPolicy, nn::q8);
BENCHMARK_TEMPLATE(BM_QuestSimSubstep, float)->Arg(30)->Arg(1);
BENCHMARK_TEMPLATE(BM_QuestSimSubstep, double)->Arg(30)->Arg(1);
BENCHMARK_MAIN();
