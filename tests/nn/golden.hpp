// Golden-vector parity harness: runs a C++ network over the deterministic input sequence that
// weights_tool/golden.py feeds PyTorch, and compares the sampled outputs.
#pragma once
#include <cmath>
#include <string>
#include <vector>

#include <doctest/doctest.h>

#include "sparsebody/io/weights_json.hpp"
#include "sparsebody/nn/network.hpp"

namespace sparsebody_test {

// Same formula as weights_tool.golden.golden_input (computed in double, then cast).
inline double golden_input(int t, int i) {
  return 0.9 * std::sin(0.05 * (t + 1.0) * (1.0 + 0.1 * (i % 7)) + 0.37 * i);
}

struct Golden {
  int steps = 0;
  std::vector<int> samples;
  sparsebody::io::Tensor out_f64, out_f32;
};

inline Golden read_golden(const std::string& path) {
  auto j = nlohmann::json::parse(sparsebody::io::read_text_file(path));
  Golden g;
  g.steps = j.at("steps").get<int>();
  g.samples = j.at("sample_steps").get<std::vector<int>>();
  g.out_f64 = sparsebody::io::detail::parse_tensor(j.at("output_f64"), path, "output_f64");
  g.out_f32 = sparsebody::io::detail::parse_tensor(j.at("output_f32"), path, "output_f32");
  return g;
}

struct ParityResult {
  double max_err_vs_f64 = 0;  // against PyTorch float64
  double max_err_vs_f32 = 0;  // against PyTorch float32
  int compared = 0;
};

// Runs `Net` (scalar T) loaded from <dir>/<name>.weights.json over the golden sequence.
template <class Net>
ParityResult run_parity(const std::string& dir, const std::string& name, const std::string& kind) {
  using T = typename Net::scalar;
  const Golden g = read_golden(dir + "/" + name + ".golden.json");
  auto w = sparsebody::nn::NetworkWeights<Net>::load(dir + "/" + name + ".weights.json", kind);
  sparsebody::nn::Network<Net> net(w);
  ParityResult r;
  std::vector<T> x(Net::in_size);
  std::size_t s = 0;
  for (int t = 0; t < g.steps; ++t) {
    for (int i = 0; i < Net::in_size; ++i) x[i] = static_cast<T>(golden_input(t, i));
    const T* y = net.step(x.data());
    if (s < g.samples.size() && g.samples[s] == t) {
      for (int o = 0; o < Net::out_size; ++o) {
        const double e64 = std::abs(double(y[o]) - g.out_f64.values[s * Net::out_size + o]);
        const double e32 = std::abs(double(y[o]) - g.out_f32.values[s * Net::out_size + o]);
        if (!(e64 <= r.max_err_vs_f64)) r.max_err_vs_f64 = std::isnan(e64) ? INFINITY : e64;
        if (!(e32 <= r.max_err_vs_f32)) r.max_err_vs_f32 = std::isnan(e32) ? INFINITY : e32;
        ++r.compared;
      }
      ++s;
    }
  }
  REQUIRE(s == g.samples.size());
  return r;
}

// float must match PyTorch float32 to 1e-5; double must match PyTorch float64 to 1e-12.
template <template <typename> class NetOf>
void check_parity(const std::string& dir, const std::string& name, const std::string& kind) {
  const ParityResult rf = run_parity<NetOf<float>>(dir, name, kind);
  const ParityResult rd = run_parity<NetOf<double>>(dir, name, kind);
  MESSAGE(name << ": float max|err| vs torch f32 " << rf.max_err_vs_f32 << " (vs f64 " << rf.max_err_vs_f64
               << "), double max|err| vs torch f64 " << rd.max_err_vs_f64 << " over " << rd.compared << " values");
  CHECK(rf.compared > 0);
  CHECK(rf.max_err_vs_f32 <= 1e-5);
  CHECK(rd.max_err_vs_f64 <= 1e-12);
}

}  // namespace sparsebody_test
