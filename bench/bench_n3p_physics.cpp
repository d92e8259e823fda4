// Per-frame cost of the Neural3Points physics mode (float simulation of the 54-DoF default avatar,
// paper-size predictor 64/128/128 on the default weights, default model-based controller):
//   BM_N3PPhysicsFrame        one whole 30 Hz frame: resampling, direct-mode predictor step + IK,
//                             reference retargeting, controller reference (RNEA), 4 simulation steps
//                             (controller torques + tracker correction + contact + ABA), fall check,
//                             output retargeting; the 10 Hz control step amortised (every 3rd frame)
//   BM_N3PPhysicsFrameCorrected  the same with a learned correction of the PD targets every frame
//                             (set_correction_policy: 4 reference kinematics, s, MLP 1008-256-256-48
//                             tanh; random weights of the trained policy's shape)
//   BM_N3PPhysicsDirectPart   the direct-mode pipeline frame alone (the predictor part)
//   BM_N3PPhysicsSimStep      one 120 Hz step: controller torques + tracker correction + Simulator::step
//   BM_N3PPhysicsReference    the per-frame controller reference (finite differences + RNEA)
// Input: a synthetic user walking a circle at 0.6 m/s (no data files besides the weights).
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <string>

#include <nlohmann/json.hpp>

#include "sparsebody/avatar/n3p_physics.hpp"

#include "n3p_default_weights.hpp"

using namespace sparsebody;

namespace {
using Physics = avatar::N3PPhysicsDefault;
// The same with int8 network weights (nn/int8.hpp): the predictor part is several times faster.
using PhysicsQ8 = avatar::N3PPhysicsQ8;

template <class P = Physics>
const typename P::Weights* weights() {
  return n3p_default_weights<P>();
}

trackers::TrackerFrame frame(long t) {
  const double T = t / 30.0, r = 1.5, a = 0.6 * T / r, s = std::sin(2 * M_PI * 0.9 * T);
  trackers::TrackerFrame f;
  f.time = T;
  const Eigen::Vector3d c(r * std::sin(a), 0, r * std::cos(a));
  const Eigen::Quaterniond yaw(Eigen::AngleAxisd(a + M_PI / 2, Eigen::Vector3d::UnitY()));
  const Eigen::Vector3d pos[3] = {c + Eigen::Vector3d(0, 1.378, 0), c + yaw * Eigen::Vector3d(0.2, 0.8, 0.1 * s),
                                  c + yaw * Eigen::Vector3d(-0.2, 0.8, -0.1 * s)};
  for (int k = 0; k < 3; ++k) {
    f.pose[k].position = trackers::to_xr(pos[k]);
    f.pose[k].orientation = trackers::to_xr(yaw);
    f.valid[k] = true;
  }
  return f;
}

// A correction policy of the trained one's shape with random weights (N(0, 0.05^2)): same cost.
template <class P>
std::shared_ptr<const typename P::CorrectionWeights> random_correction() {
  std::mt19937 rng(5);
  std::normal_distribution<double> g(0.0, 0.05);
  const int sizes[4] = {1008, 256, 256, 48};
  nlohmann::json d;
  d["format"] = "sparsebody-weights";
  d["version"] = 1;
  d["kind"] = "n3p_correction_policy";
  d["meta"] = {{"input_size", 1008}, {"output_size", 48}, {"action_scale", 0.2}};
  for (int l = 0; l < 3; ++l) {
    std::vector<double> wv(std::size_t(sizes[l + 1]) * sizes[l]), bv(sizes[l + 1]);
    for (auto& x : wv) x = g(rng);
    for (auto& x : bv) x = g(rng);
    const std::string n = "layers." + std::to_string(l);
    d["tensors"][n + ".weight"] = {{"shape", {sizes[l + 1], sizes[l]}}, {"data", wv}};
    d["tensors"][n + ".bias"] = {{"shape", {sizes[l + 1]}}, {"data", bv}};
  }
  return P::Correction::parse(d.dump(), "random correction policy");
}

template <class P>
void physics_frame(benchmark::State& state, bool corrected = false) {
  const auto* w = weights<P>();
  if (!w) return state.SkipWithError("default weights not found");
  P p(*w);
  if (corrected) p.set_correction_policy(random_correction<P>());
  long t = 0;
  for (; t < 30; ++t) p.push(frame(t));
  double passes = 0, frames = 0;
  for (auto _ : state) {
    p.push(frame(t++));
    benchmark::DoNotOptimize(p.world().position[0]);
    passes += p.simulator().last_passes();  // ABA solves of the frame's last 120 Hz step
    frames += 1;
  }
  state.counters["aba_passes"] = frames > 0 ? passes / frames : 0;
  state.counters["falls_per_s"] = benchmark::Counter(double(p.falls()) * 30.0 / double(t));
  state.counters["residual_N"] = p.residual_stats().force_mean();
}
void BM_N3PPhysicsFrame(benchmark::State& s) { physics_frame<Physics>(s); }
void BM_N3PPhysicsFrameQ8(benchmark::State& s) { physics_frame<PhysicsQ8>(s); }
void BM_N3PPhysicsFrameCorrected(benchmark::State& s) { physics_frame<Physics>(s, true); }
void BM_N3PPhysicsFrameCorrectedQ8(benchmark::State& s) { physics_frame<PhysicsQ8>(s, true); }
BENCHMARK(BM_N3PPhysicsFrame)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_N3PPhysicsFrameQ8)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_N3PPhysicsFrameCorrected)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_N3PPhysicsFrameCorrectedQ8)->Unit(benchmark::kMicrosecond);

void BM_N3PPhysicsDirectPart(benchmark::State& state) {
  const auto* w = weights();
  if (!w) return state.SkipWithError("default weights not found");
  Physics::Direct p(*w);
  long t = 0;
  for (; t < 30; ++t) p.push(frame(t));
  for (auto _ : state) {
    p.push(frame(t++));
    benchmark::DoNotOptimize(p.world().position[0]);
  }
}
BENCHMARK(BM_N3PPhysicsDirectPart)->Unit(benchmark::kMicrosecond);

struct SimFixture {
  Physics p{*weights()};
  const Physics::ModelT& m = p.model();
  dynamics::Simulator<float, 24, 72> sim{m};
  control::ModelBasedController<float, 24, 72> ctl{m};
  control::TrackerCorrection<float, 24, 72> tc{m};
  Physics::VecQ q0 = m.neutral_configuration();
  Physics::VecV tau = Physics::VecV::Zero(m.nv);
  double contact[2] = {1, 1};
};

void BM_N3PPhysicsSimStep(benchmark::State& state) {
  if (!weights()) return state.SkipWithError("default weights not found");
  SimFixture f;
  const dynamics::Vec3<float> target[2] = {dynamics::Vec3<float>(0.5f, 1.2f, 0.3f), dynamics::Vec3<float>(-0.5f, 1.2f, 0.3f)};
  const bool present[2] = {true, true};
  f.ctl.set_reference(f.m, f.q0, f.q0, f.q0, 1.0f / 30, f.contact);
  Physics::VecV v0 = Physics::VecV::Zero(f.m.nv);
  long k = 0;
  for (auto _ : state) {
    if (++k % 60 == 0) f.sim.set_state(f.q0, v0);  // stay standing on the floor
    f.ctl.apply(f.m, f.sim, 0.5f, f.tau);
    f.tc.apply(f.m, f.sim.data(), target, present, f.tau);
    f.sim.torques() = f.tau;
    benchmark::DoNotOptimize(f.sim.step(1.0f / 120));
  }
}
BENCHMARK(BM_N3PPhysicsSimStep)->Unit(benchmark::kMicrosecond);

void BM_N3PPhysicsReference(benchmark::State& state) {
  if (!weights()) return state.SkipWithError("default weights not found");
  SimFixture f;
  Physics::VecQ q1 = f.q0, q2 = f.q0;
  q1(0) += 0.02f;
  q2(0) += 0.04f;
  for (auto _ : state) {
    f.ctl.set_reference(f.m, f.q0, q1, q2, 1.0f / 30, f.contact);
    benchmark::DoNotOptimize(f.ctl.feedforward()(10));
  }
}
BENCHMARK(BM_N3PPhysicsReference)->Unit(benchmark::kMicrosecond);
}  // namespace

BENCHMARK_MAIN();
