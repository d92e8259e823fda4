// The papers' MLPs against XNNPACK (Debian libxnnpack-dev 0.0~git20220216, the backend of TFLite),
// in the same run: batch 1, one thread (NULL threadpool), identical random weights on both sides.
//   sparsebody/<shape>             nn::MLPStored, float weights          (nn::Network::step)
//   sparsebody/<shape>_q8weights   the same, int8 weights ("q8": per-row weight scales, dynamic
//                                  per-vector input quantization, float bias / activations)
//   xnnpack/<shape>_f32            xnn_*_fully_connected_nc_f32 operators, one per layer
//   xnnpack/<shape>_qs8            the fully-integer TFLite-style pipeline: convert_nc_f32_qs8 ->
//                                  fully_connected_nc_qs8 (+ tanh_nc_qs8) per layer -> convert_nc_qs8_f32,
//                                  per-tensor scales calibrated on 32 random inputs (this XNNPACK version
//                                  has no per-channel or dynamically quantized fully-connected operator)
// Activations: ReLU is the operator's fused output clamp on both XNNPACK paths. This XNNPACK has no f32
// tanh operator, so the f32 path writes tanh(z) = 2 sigmoid(2z) - 1 exactly with its sigmoid_nc_f32
// operator: the factors 2 and the "- 1" are folded into the next layer's weights and bias, and only the
// network's output gets a plain loop y = 2 s - 1 (inside the timed step). The qs8 path uses
// tanh_nc_qs8 (output scale 1/128, as TFLite). "_linear" shapes have no activation on either side.
// Setup checks every path's output against a double-precision reference of the same weights and
// aborts if a float path is off by more than 1e-4 or an int8 path by more than 1e-1, both relative to
// the reference output's largest magnitude (max_i |y_i - r_i| / max_i |r_i|); the errors are printed.
// Run: build/bench/bench_xnnpack --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// The ratios at the end are times, sparsebody / XNNPACK (< 1: sparsebody faster); the issue's
// targets are float <= 1/1.2 = 0.833 and int8 <= 1/1.5 = 0.667.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include <benchmark/benchmark.h>
#include <xnnpack.h>

#include "nn/random_tables.hpp"
#include "ratio_report.hpp"
#include "sparsebody/character/avatar.hpp"
#include "sparsebody/control/questsim_observation.hpp"
#include "sparsebody/networks/policy_nets.hpp"
#include "sparsebody/nn/mlp.hpp"
#include "sparsebody/nn/network.hpp"
#include "sparsebody/nn/storage.hpp"

using namespace sparsebody;

namespace {

// The QuestSim policy's input / output on the library's default avatar (observation layout of
// control/questsim_observation.hpp with 6 future frames; one action per non-root DoF), and on the
// paper's character (16 links, 33 DoF, 5 future frames: the shape bench_networks uses).
constexpr int kQsIn = control::QuestSimLayout<character::kDefaultAvatarBodies, character::kDefaultAvatarJointDofs, 6>::size;
constexpr int kQsOut = character::kDefaultAvatarJointDofs;
static_assert(kQsIn == 607 && kQsOut == 48, "the default avatar's QuestSim layout changed: rename the shapes");
static_assert(control::quest_sim_observation_size(16, 33, 5) == 475, "paper character's QuestSim observation");

enum class Act { Identity, ReLU, Tanh };

[[noreturn]] void fail(const std::string& msg) {
  std::fprintf(stderr, "bench_xnnpack: %s\n", msg.c_str());
  std::exit(1);
}
void check(xnn_status s, const char* what) {
  if (s != xnn_status_success) fail(std::string(what) + " failed (xnn_status " + std::to_string(int(s)) + ")");
}

struct Layer {
  int in = 0, out = 0;
  std::vector<double> W, b;  // W: [out, in] row-major, as torch.nn.Linear and XNNPACK (no TRANSPOSE flag)
};

// Random layers, PyTorch-like scale (weights ~ N(0, 1/in), biases ~ N(0, 0.1^2)), float-representable.
std::vector<Layer> random_layers(const std::vector<int>& sizes, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<Layer> L;
  for (std::size_t i = 0; i + 1 < sizes.size(); ++i) {
    Layer l;
    l.in = sizes[i];
    l.out = sizes[i + 1];
    std::normal_distribution<double> dw(0.0, 1.0 / std::sqrt(double(l.in))), db(0.0, 0.1);
    l.W.resize(std::size_t(l.in) * l.out);
    l.b.resize(l.out);
    for (auto& v : l.W) v = double(float(dw(rng)));
    for (auto& v : l.b) v = double(float(db(rng)));
    L.push_back(std::move(l));
  }
  return L;
}
io::TensorTable to_table(const std::vector<Layer>& L) {
  io::TensorTable t("random");
  for (std::size_t i = 0; i < L.size(); ++i) {
    io::Tensor w, b;
    w.shape = {L[i].out, L[i].in};
    w.values = L[i].W;
    b.shape = {L[i].out};
    b.values = L[i].b;
    t.tensors()["layers." + std::to_string(i) + ".weight"] = std::move(w);
    t.tensors()["layers." + std::to_string(i) + ".bias"] = std::move(b);
  }
  return t;
}
double apply(Act a, double z) { return a == Act::ReLU ? std::max(z, 0.0) : a == Act::Tanh ? std::tanh(z) : z; }

// Double-precision forward; pre[l] receives layer l's pre-activation when given.
std::vector<double> reference(const std::vector<Layer>& L, const std::vector<Act>& act, const std::vector<float>& x,
                              std::vector<std::vector<double>>* pre = nullptr) {
  std::vector<double> a(x.begin(), x.end());
  if (pre) pre->assign(L.size(), {});
  for (std::size_t l = 0; l < L.size(); ++l) {
    std::vector<double> z(L[l].out);
    for (int r = 0; r < L[l].out; ++r) {
      double s = L[l].b[r];
      for (int c = 0; c < L[l].in; ++c) s += L[l].W[std::size_t(r) * L[l].in + c] * a[c];
      z[r] = s;
    }
    if (pre) (*pre)[l] = z;
    for (auto& v : z) v = apply(act[l], v);
    a = std::move(z);
  }
  return a;
}

// XNNPACK f32: one fully-connected operator per layer (ReLU fused as the output clamp), tanh as
// sigmoid_nc_f32 on doubled pre-activations with the affine map folded into the next layer (see top).
class XnnF32 {
 public:
  XnnF32(const std::vector<Layer>& L, const std::vector<Act>& act) : out_n_(L.back().out) {
    constexpr std::size_t pad = XNN_EXTRA_BYTES / sizeof(float);
    in_.assign(L.front().in + pad, 0.f);
    const float* cur = in_.data();
    bool prev_tanh = false;  // the current buffer holds s = sigmoid(2z) of a tanh layer
    for (std::size_t l = 0; l < L.size(); ++l) {
      const Layer& ly = L[l];
      const bool tanh = act[l] == Act::Tanh;
      const double k = tanh ? 2.0 : 1.0;  // tanh: this FC outputs 2z
      std::vector<float> W(ly.W.size()), b(ly.out);
      for (int r = 0; r < ly.out; ++r) {
        double rowsum = 0;
        for (int c = 0; c < ly.in; ++c) {
          const double w = ly.W[std::size_t(r) * ly.in + c];
          rowsum += w;
          W[std::size_t(r) * ly.in + c] = float(prev_tanh ? 2.0 * k * w : k * w);  // W (2s - 1) = 2W s - W 1
        }
        b[r] = float(prev_tanh ? k * (ly.b[r] - rowsum) : k * ly.b[r]);
      }
      bufs_.emplace_back(ly.out + pad, 0.f);
      float* z = bufs_.back().data();
      const float lo = act[l] == Act::ReLU ? 0.f : -INFINITY;
      xnn_operator_t op = nullptr;
      check(xnn_create_fully_connected_nc_f32(ly.in, ly.out, ly.in, ly.out, W.data(), b.data(), lo, INFINITY, 0, &op),
            "xnn_create_fully_connected_nc_f32");
      check(xnn_setup_fully_connected_nc_f32(op, 1, cur, z, nullptr), "xnn_setup_fully_connected_nc_f32");
      ops_.push_back(op);
      cur = z;
      if (tanh) {
        bufs_.emplace_back(ly.out + pad, 0.f);
        float* s = bufs_.back().data();
        check(xnn_create_sigmoid_nc_f32(ly.out, ly.out, ly.out, 0, &op), "xnn_create_sigmoid_nc_f32");
        check(xnn_setup_sigmoid_nc_f32(op, 1, cur, s, nullptr), "xnn_setup_sigmoid_nc_f32");
        ops_.push_back(op);
        cur = s;
      }
      prev_tanh = tanh;
    }
    last_ = cur;
    tanh_out_ = prev_tanh;
    y_.assign(out_n_, 0.f);
  }
  XnnF32(const XnnF32&) = delete;
  XnnF32& operator=(const XnnF32&) = delete;
  ~XnnF32() {
    for (auto op : ops_) xnn_delete_operator(op);
  }
  float* input() { return in_.data(); }
  const float* step() {
    for (auto op : ops_) xnn_run_operator(op, nullptr);
    if (!tanh_out_) return last_;
    for (int i = 0; i < out_n_; ++i) y_[i] = 2.f * last_[i] - 1.f;
    return y_.data();
  }

 private:
  int out_n_;
  std::vector<float> in_, y_;
  std::vector<std::vector<float>> bufs_;
  std::vector<xnn_operator_t> ops_;
  const float* last_ = nullptr;
  bool tanh_out_ = false;
};

// Asymmetric per-tensor int8 quantization of the range [lo, hi] (which is widened to hold 0).
struct QParams {
  float scale;
  int8_t zp;
};
QParams qparams(double lo, double hi) {
  lo = std::min(lo, 0.0);
  hi = std::max(hi, 0.0);
  const double scale = std::max(hi - lo, 1e-8) / 255.0;
  const long zp = std::lround(-128.0 - lo / scale);
  return {float(scale), int8_t(std::clamp(zp, -128L, 127L))};
}

// XNNPACK qs8 (TFLite full-integer style): static per-tensor activation scales from the calibration
// ranges, per-tensor symmetric weight scale (all this version's qs8 fully-connected operator takes),
// int32 bias at scale s_in * s_w, ReLU as the clamp at the output zero point, tanh_nc_qs8 for tanh.
class XnnQs8 {
 public:
  XnnQs8(const std::vector<Layer>& L, const std::vector<Act>& act, const std::vector<std::vector<float>>& calib)
      : out_n_(L.back().out) {
    // Ranges of the input and of every pre-activation over the calibration inputs.
    double xlo = 0, xhi = 0;
    std::vector<double> zlo(L.size(), 0.0), zhi(L.size(), 0.0);
    for (const auto& x : calib) {
      std::vector<std::vector<double>> pre;
      reference(L, act, x, &pre);
      for (float v : x) xlo = std::min(xlo, double(v)), xhi = std::max(xhi, double(v));
      for (std::size_t l = 0; l < L.size(); ++l)
        for (double v : pre[l]) zlo[l] = std::min(zlo[l], v), zhi[l] = std::max(zhi[l], v);
    }
    constexpr std::size_t pad = XNN_EXTRA_BYTES;
    in_.assign(L.front().in + pad / sizeof(float), 0.f);
    QParams q = qparams(xlo, xhi);
    bufs_.emplace_back(L.front().in + pad, int8_t(0));
    int8_t* cur = bufs_.back().data();
    xnn_operator_t op = nullptr;
    check(xnn_create_convert_nc_f32_qs8(L.front().in, L.front().in, L.front().in, q.scale, q.zp, -128, 127, 0, &op),
          "xnn_create_convert_nc_f32_qs8");
    check(xnn_setup_convert_nc_f32_qs8(op, 1, in_.data(), cur, nullptr), "xnn_setup_convert_nc_f32_qs8");
    ops_.push_back(op);
    for (std::size_t l = 0; l < L.size(); ++l) {
      const Layer& ly = L[l];
      double wmax = 0;
      for (double w : ly.W) wmax = std::max(wmax, std::abs(w));
      const double ws = std::max(wmax, 1e-12) / 127.0;
      std::vector<int8_t> W(ly.W.size());
      for (std::size_t i = 0; i < W.size(); ++i)
        W[i] = int8_t(std::clamp(std::lround(ly.W[i] / ws), -127L, 127L));
      std::vector<int32_t> b(ly.out);
      for (int r = 0; r < ly.out; ++r) b[r] = int32_t(std::lround(ly.b[r] / (double(q.scale) * ws)));
      const QParams qz = act[l] == Act::ReLU ? qparams(0.0, zhi[l]) : qparams(zlo[l], zhi[l]);
      const int8_t lo = act[l] == Act::ReLU ? qz.zp : int8_t(-128);
      bufs_.emplace_back(ly.out + pad, int8_t(0));
      int8_t* z = bufs_.back().data();
      check(xnn_create_fully_connected_nc_qs8(ly.in, ly.out, ly.in, ly.out, q.zp, q.scale, float(ws), W.data(), b.data(),
                                              qz.zp, qz.scale, lo, 127, 0, &op),
            "xnn_create_fully_connected_nc_qs8");
      check(xnn_setup_fully_connected_nc_qs8(op, 1, cur, z, nullptr), "xnn_setup_fully_connected_nc_qs8");
      ops_.push_back(op);
      cur = z;
      q = qz;
      if (act[l] == Act::Tanh) {
        const QParams qt{1.f / 128.f, 0};
        bufs_.emplace_back(ly.out + pad, int8_t(0));
        int8_t* t = bufs_.back().data();
        check(xnn_create_tanh_nc_qs8(ly.out, ly.out, ly.out, qz.zp, qz.scale, qt.zp, qt.scale, -128, 127, 0, &op),
              "xnn_create_tanh_nc_qs8");
        check(xnn_setup_tanh_nc_qs8(op, 1, cur, t, nullptr), "xnn_setup_tanh_nc_qs8");
        ops_.push_back(op);
        cur = t;
        q = qt;
      }
    }
    y_.assign(out_n_ + pad / sizeof(float), 0.f);
    check(xnn_create_convert_nc_qs8_f32(out_n_, out_n_, out_n_, q.scale, q.zp, 0, &op), "xnn_create_convert_nc_qs8_f32");
    check(xnn_setup_convert_nc_qs8_f32(op, 1, cur, y_.data(), nullptr), "xnn_setup_convert_nc_qs8_f32");
    ops_.push_back(op);
  }
  XnnQs8(const XnnQs8&) = delete;
  XnnQs8& operator=(const XnnQs8&) = delete;
  ~XnnQs8() {
    for (auto op : ops_) xnn_delete_operator(op);
  }
  float* input() { return in_.data(); }
  const float* step() {
    for (auto op : ops_) xnn_run_operator(op, nullptr);
    return y_.data();
  }

 private:
  int out_n_;
  std::vector<float> in_, y_;
  std::vector<std::vector<int8_t>> bufs_;
  std::vector<xnn_operator_t> ops_;
};

double rel_error(const float* y, const std::vector<double>& ref) {
  double e = 0, m = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) e = std::max(e, std::abs(double(y[i]) - ref[i])), m = std::max(m, std::abs(ref[i]));
  return e / std::max(m, 1e-30);
}

constexpr double kFloatTol = 1e-4, kInt8Tol = 1e-1;

template <class Stepper>
void bench_stepper(benchmark::State& st, std::shared_ptr<Stepper> s) {
  for (auto _ : st) {
    const float* y = s->step();
    benchmark::DoNotOptimize(y);
    benchmark::ClobberMemory();
  }
}

// sparsebody's side: an nn::Network on its fixed input, stepped like the XNNPACK operators.
template <class Net>
struct SbStepper {
  std::shared_ptr<const nn::NetworkWeights<Net>> w;
  nn::Network<Net> net;
  std::vector<float> x;
  SbStepper(std::shared_ptr<const nn::NetworkWeights<Net>> w_, std::vector<float> x_) : w(w_), net(w_), x(std::move(x_)) {}
  const float* step() { return net.step(x.data()); }
};

template <class A>
constexpr Act act_of() {
  return std::is_same_v<A, nn::ReLU> ? Act::ReLU : std::is_same_v<A, nn::Tanh> ? Act::Tanh : Act::Identity;
}

// One shape: the four benchmarks, their checks and their two ratios.
template <class HiddenAct, class OutAct, int... S>
void add_shape(const std::string& name, unsigned seed) {
  using NetF = nn::Named<networks::policy_names::kLayers, nn::MLPStored<float, float, HiddenAct, OutAct, S...>>;
  using NetQ = nn::Named<networks::policy_names::kLayers, nn::MLPStored<float, nn::q8, HiddenAct, OutAct, S...>>;
  const std::vector<int> sizes{S...};
  const std::vector<Layer> L = random_layers(sizes, seed);
  std::vector<Act> act(L.size(), act_of<HiddenAct>());
  act.back() = act_of<OutAct>();

  std::mt19937 rng(seed + 100);
  std::normal_distribution<float> d(0.f, 1.f);
  auto random_input = [&] {
    std::vector<float> x(sizes.front());
    for (auto& v : x) v = d(rng);
    return x;
  };
  const std::vector<float> x = random_input();  // the benchmarked input (also in the calibration set)
  std::vector<std::vector<float>> calib{x};
  for (int i = 0; i < 31; ++i) calib.push_back(random_input());
  const std::vector<double> ref = reference(L, act, x);

  auto sf = std::make_shared<SbStepper<NetF>>(sparsebody_test::weights_from_table<NetF>(to_table(L), "mlp"), x);
  auto sq = std::make_shared<SbStepper<NetQ>>(sparsebody_test::weights_from_table<NetQ>(to_table(L), "mlp"), x);
  auto xf = std::make_shared<XnnF32>(L, act);
  auto xq = std::make_shared<XnnQs8>(L, act, calib);
  std::copy(x.begin(), x.end(), xf->input());
  std::copy(x.begin(), x.end(), xq->input());

  const double e_sf = rel_error(sf->step(), ref), e_sq = rel_error(sq->step(), ref);
  const double e_xf = rel_error(xf->step(), ref), e_xq = rel_error(xq->step(), ref);
  const float* pxf = xf->step();
  const std::vector<double> yxf(pxf, pxf + ref.size());
  const double e_pair = rel_error(sf->step(), yxf);
  std::printf("  %-34s rel. error vs double: sparsebody float %.1e, q8 %.1e; XNNPACK f32 %.1e, qs8 %.1e; "
              "sparsebody float vs XNNPACK f32 %.1e\n",
              name.c_str(), e_sf, e_sq, e_xf, e_xq, e_pair);
  auto need = [&](double e, double tol, const char* what) {
    if (!(e <= tol))
      fail(name + ": " + what + " differs from the double reference by " + std::to_string(e) +
           " (relative to the output's largest magnitude), above the tolerance " + std::to_string(tol));
  };
  need(e_sf, kFloatTol, "sparsebody float");
  need(e_xf, kFloatTol, "XNNPACK f32");
  need(e_pair, 2 * kFloatTol, "sparsebody float vs XNNPACK f32");
  need(e_sq, kInt8Tol, "sparsebody q8");
  need(e_xq, kInt8Tol, "XNNPACK qs8");

  auto reg = [](const std::string& n, auto fn) { benchmark::RegisterBenchmark(n.c_str(), fn)->Unit(benchmark::kMicrosecond); };
  reg("sparsebody/" + name, [sf](benchmark::State& s) { bench_stepper(s, sf); });
  reg("sparsebody/" + name + "_q8weights", [sq](benchmark::State& s) { bench_stepper(s, sq); });
  reg("xnnpack/" + name + "_f32", [xf](benchmark::State& s) { bench_stepper(s, xf); });
  reg("xnnpack/" + name + "_qs8", [xq](benchmark::State& s) { bench_stepper(s, xq); });
  sparsebody_bench::add_ratio(name + " float: sparsebody / XNNPACK f32", "sparsebody/" + name, "xnnpack/" + name + "_f32");
  sparsebody_bench::add_ratio(name + " int8: sparsebody q8 / XNNPACK qs8", "sparsebody/" + name + "_q8weights",
                              "xnnpack/" + name + "_qs8");
}

void print_target() {
  std::ifstream f("/proc/cpuinfo");
  std::string line, model = "unknown CPU";
  while (std::getline(f, line))
    if (line.rfind("model name", 0) == 0) {
      model = line.substr(line.find(':') + 2);
      break;
    }
  std::printf("CPU: %s; sparsebody build: %d float lanes, int8 kernel %s; XNNPACK picks its kernels at run time (CPUID)\n",
              model.c_str(), nn::kLanes<float>, nn::q8_kernel_in_use());
}

}  // namespace

int main(int argc, char** argv) {
  print_target();
  check(xnn_initialize(nullptr), "xnn_initialize");
  std::printf("Output checks (tolerances: float %.0e, int8 %.0e; max |y - ref| / max |ref|):\n", kFloatTol, kInt8Tol);
  // QuestSim policy, tanh on every layer: the library's default avatar and the paper's character.
  add_shape<nn::Tanh, nn::Tanh, kQsIn, 400, 300, 200, kQsOut>("QuestSim_607_400_300_200_48", 11);
  add_shape<nn::Tanh, nn::Tanh, 475, 400, 300, 200, 33>("QuestSim_475_400_300_200_33", 12);
  // The same layers without activations (what both sides' fully-connected kernels alone cost).
  add_shape<nn::Identity, nn::Identity, kQsIn, 400, 300, 200, kQsOut>("QuestSim_607_400_300_200_48_linear", 11);
  // Neural3Points control policy (ReLU hidden layers, linear output).
  add_shape<nn::ReLU, nn::Identity, 868, 256, 256, 72>("N3P_policy_868_256_256_72", 13);
  // LoBSTr's dense part after the GRU: latent Linear(H->256)+ReLU, then the pose (48) and contact (4)
  // heads as one 52-wide linear layer (the contact softmax left out on both sides).
  add_shape<nn::ReLU, nn::Identity, 1024, 256, 52>("LoBSTr_head_1024_256_52", 14);
  add_shape<nn::ReLU, nn::Identity, 256, 256, 52>("LoBSTr_head_256_256_52", 15);
  const int rc = sparsebody_bench::run_with_ratios(argc, argv, "sparsebody vs XNNPACK (time ratio; < 1: sparsebody faster)");
  benchmark::ClearRegisteredBenchmarks();  // they hold the operators: delete them before xnn_deinitialize
  xnn_deinitialize();
  return rc;
}
