// Layer-level checks against independent scalar implementations written here from the formulas
// (PyTorch parity is in test_parity_*.cpp), plus state handling and weight sharing.
#include <cmath>
#include <random>
#include <limits>
#include <thread>
#include <vector>

#include <doctest/doctest.h>

#include "nn/random_tables.hpp"
#include "sparsebody/networks/lobstr_net.hpp"
#include "sparsebody/nn/activation.hpp"
#include "sparsebody/nn/compose.hpp"
#include "sparsebody/nn/dense.hpp"
#include "sparsebody/nn/gru.hpp"
#include "sparsebody/nn/network.hpp"

using namespace sparsebody;
using namespace sparsebody_test;

TEST_CASE_TEMPLATE("gemv matches a naive product for sizes that are not multiples of the SIMD width", T, float, double) {
  std::mt19937 rng(7);
  std::normal_distribution<double> d(0, 1);
  for (int rows : {1, 3, 15, 16, 17, 33, 127, 128, 129, 300, 1031}) {
    for (int cols : {1, 5, 37, 64, 130}) {
      io::TensorTable t("test");
      add_random(t, "w", {rows, cols}, rng, 1.0);
      add_random(t, "b", {rows}, rng, 1.0);
      nn::WeightStore<T> store;
      nn::ParamBinder<T> binder(t, store);
      const nn::PanelMatrix<T> W = binder.matrix("w", rows, cols);
      const T* b = binder.vector("b", rows);
      // x exactly `cols` long (no padding) and deliberately misaligned by one element
      std::vector<T> xs(cols + 1);
      for (auto& v : xs) v = static_cast<T>(d(rng));
      const T* x = xs.data() + 1;
      std::vector<T, xsimd::aligned_allocator<T, 64>> y(nn::padded<T>(rows) + 1, T(-7));
      nn::gemv(W, x, b, y.data());
      double max_err = 0;
      for (int r = 0; r < rows; ++r) {
        double ref = t.tensors()["b"].values[r];
        for (int c = 0; c < cols; ++c) ref += t.tensors()["w"].values[std::size_t(r) * cols + c] * double(x[c]);
        max_err = std::max(max_err, std::abs(ref - double(y[r])));
      }
      const double tol = std::is_same_v<T, float> ? 2e-4 * std::sqrt(double(cols)) : 1e-12 * std::sqrt(double(cols));
      CHECK_MESSAGE(max_err <= tol, "rows " << rows << " cols " << cols);
      CHECK(y[nn::padded<T>(rows)] == T(-7));  // nothing written past the padded output
      for (int r = rows; r < nn::padded<T>(rows); ++r) CHECK(y[r] == T(0));  // zero padding rows
    }
  }
}

template <typename T, int N, typename Act>
std::vector<double> apply_act(const std::vector<double>& in) {
  nn::PaddedVector<T, N> buf;
  for (int i = 0; i < N; ++i) buf.v[i] = static_cast<T>(in[i]);
  Act::template apply<T, N>(buf.data());
  return std::vector<double>(buf.v, buf.v + N);
}

TEST_CASE_TEMPLATE("activations match their scalar formulas", T, float, double) {
  constexpr int N = 37;
  std::vector<double> x(N);
  for (int i = 0; i < N; ++i) x[i] = -9.0 + 18.0 * i / (N - 1);
  const double tol = std::is_same_v<T, float> ? 2e-7 : 1e-15;
  auto relu = apply_act<T, N, nn::ReLU>(x), th = apply_act<T, N, nn::Tanh>(x), sg = apply_act<T, N, nn::Sigmoid>(x),
       elu = apply_act<T, N, nn::ELU>(x), id = apply_act<T, N, nn::Identity>(x);
  for (int i = 0; i < N; ++i) {
    const double xi = double(T(x[i]));
    CHECK(relu[i] == doctest::Approx(std::max(xi, 0.0)).epsilon(tol));
    CHECK(std::abs(th[i] - std::tanh(xi)) <= 2 * tol);
    CHECK(std::abs(sg[i] - 1.0 / (1.0 + std::exp(-xi))) <= 2 * tol);
    CHECK(std::abs(elu[i] - (xi > 0 ? xi : std::expm1(xi))) <= 4 * tol);
    CHECK(id[i] == xi);
  }
  auto sm = apply_act<T, 6, nn::Softmax<3>>({1000.0, 1001.0, 999.0, -1.0, 0.0, 1.0});  // max-subtracted: no overflow
  for (int g = 0; g < 2; ++g) {
    double s = 0;
    for (int i = 0; i < 3; ++i) s += sm[g * 3 + i];
    CHECK(s == doctest::Approx(1.0).epsilon(tol * 4));
  }
  CHECK(sm[1] == doctest::Approx(std::exp(1.0) / (1 + std::exp(1.0) + std::exp(-1.0))).epsilon(1e-6));
}

// Scalar GRU step written from PyTorch's documented equations (an oracle independent of gru.hpp).
static void gru_reference(const io::TensorTable& t, int in, int h, int layers, const std::vector<double>& x,
                          std::vector<std::vector<double>>& hs) {
  auto sig = [](double v) { return 1.0 / (1.0 + std::exp(-v)); };
  std::vector<double> inp = x;
  for (int k = 0; k < layers; ++k) {
    const std::string s = "_l" + std::to_string(k);
    const auto& wih = t.tensors().at("g.weight_ih" + s).values;
    const auto& whh = t.tensors().at("g.weight_hh" + s).values;
    const auto& bih = t.tensors().at("g.bias_ih" + s).values;
    const auto& bhh = t.tensors().at("g.bias_hh" + s).values;
    const int ink = k == 0 ? in : h;
    std::vector<double> hn(h);
    for (int i = 0; i < h; ++i) {
      double gi[3], gh[3];
      for (int g = 0; g < 3; ++g) {
        gi[g] = bih[g * h + i];
        gh[g] = bhh[g * h + i];
        for (int c = 0; c < ink; ++c) gi[g] += wih[std::size_t(g * h + i) * ink + c] * inp[c];
        for (int c = 0; c < h; ++c) gh[g] += whh[std::size_t(g * h + i) * h + c] * hs[k][c];
      }
      const double r = sig(gi[0] + gh[0]), z = sig(gi[1] + gh[1]);
      const double n = std::tanh(gi[2] + r * gh[2]);
      hn[i] = (1 - z) * n + z * hs[k][i];
    }
    hs[k] = hn;
    inp = hn;
  }
}

inline constexpr char kG[] = "g";

TEST_CASE_TEMPLATE("GRU stack equals the scalar PyTorch-equation oracle over 200 steps", T, float, double) {
  constexpr int In = 7, H = 19, L = 3;
  using Net = nn::Named<kG, nn::GRU<T, In, H, L>>;
  std::mt19937 rng(3);
  io::TensorTable t("test");
  add_gru(t, "g.", In, H, L, rng);
  auto w = weights_from_table<Net>(t, "gru");
  nn::Network<Net> net(w);
  std::vector<std::vector<double>> hs(L, std::vector<double>(H, 0.0));
  double max_err = 0;
  for (int step = 0; step < 200; ++step) {
    std::vector<double> x(In);
    std::vector<T> xt(In);
    for (int i = 0; i < In; ++i) xt[i] = static_cast<T>(x[i] = std::sin(0.1 * step + i));
    for (int i = 0; i < In; ++i) x[i] = double(xt[i]);
    gru_reference(t, In, H, L, x, hs);
    const T* y = net.step(xt.data());
    for (int i = 0; i < H; ++i) max_err = std::max(max_err, std::abs(double(y[i]) - hs[L - 1][i]));
  }
  CHECK(max_err <= (std::is_same_v<T, float> ? 1e-5 : 1e-13));
  // The padding lanes of every hidden state stay exactly zero.
  for (int k = 0; k < L; ++k)
    for (int i = H; i < nn::padded<T>(H); ++i) CHECK(net.state().h[k][i] == T(0));
}

TEST_CASE("hidden state can be read, written and reset; instances sharing weights are independent") {
  using Net = sparsebody::networks::LoBSTrNet<float, 33, 16>;
  auto w = weights_from_table<Net>(random_lobstr_table(33, 16, 5), "lobstr");
  nn::Network<Net> a(w), b(w);
  std::vector<float> x(37), y0(52), y1(52);
  for (int i = 0; i < 37; ++i) x[i] = 0.1f * i;
  const float* y = a.step(x.data());
  std::copy(y, y + 52, y0.begin());
  auto& ha = std::get<0>(a.state().layers).h[0];
  std::vector<float> saved(ha, ha + 33);
  for (int s = 0; s < 10; ++s) a.step(x.data());
  // b is untouched by a's steps: its first step equals a's first step
  y = b.step(x.data());
  for (int i = 0; i < 52; ++i) CHECK(y[i] == y0[i]);
  // writing a saved hidden state reproduces the continuation exactly
  auto& hb = std::get<0>(b.state().layers).h[0];
  std::copy(saved.begin(), saved.end(), hb);
  a.reset();
  a.step(x.data());
  auto& ha2 = std::get<0>(a.state().layers).h[0];
  std::copy(saved.begin(), saved.end(), ha2);
  const float* ya = a.step(x.data());
  std::copy(ya, ya + 52, y1.begin());
  y = b.step(x.data());
  for (int i = 0; i < 52; ++i) CHECK(y[i] == y1[i]);
  // reset returns to the zero state: first output again
  b.reset();
  y = b.step(x.data());
  for (int i = 0; i < 52; ++i) CHECK(y[i] == y0[i]);
  // contact outputs are probabilities per foot
  CHECK(y[48] + y[49] == doctest::Approx(1.0f));
  CHECK(y[50] + y[51] == doctest::Approx(1.0f));
}

TEST_CASE("one set of weights serves many threads") {
  using Net = sparsebody::networks::LoBSTrNet<float, 64, 32>;
  auto w = weights_from_table<Net>(random_lobstr_table(64, 32, 9), "lobstr");
  auto run = [&](int seed, std::vector<float>& out) {
    nn::Network<Net> n(w);
    std::vector<float> x(37);
    for (int s = 0; s < 300; ++s) {
      for (int i = 0; i < 37; ++i) x[i] = std::sin(0.03f * s * (seed + 1) + i);
      const float* y = n.step(x.data());
      out.assign(y, y + 52);
    }
  };
  std::vector<std::vector<float>> serial(4), threaded(4);
  for (int k = 0; k < 4; ++k) run(k, serial[k]);
  std::vector<std::thread> th;
  for (int k = 0; k < 4; ++k) th.emplace_back(run, k, std::ref(threaded[k]));
  for (auto& x : th) x.join();
  for (int k = 0; k < 4; ++k) CHECK(serial[k] == threaded[k]);
  CHECK(serial[0] != serial[1]);
}

TEST_CASE("step_guarded: NaN/Inf input is rejected without touching the state; a diverged output resets it") {
  using Net = nn::Named<kG, nn::GRU<float, 3, 5, 1>>;
  std::mt19937 rng(11);
  io::TensorTable t("test");
  add_gru(t, "g.", 3, 5, 1, rng);
  auto w = weights_from_table<Net>(t, "gru");
  nn::Network<Net> a(w), b(w);
  const float good[3] = {0.1f, -0.2f, 0.3f};
  const float nan_in[3] = {0.1f, std::numeric_limits<float>::quiet_NaN(), 0.3f};
  const float inf_in[3] = {std::numeric_limits<float>::infinity(), 0.f, 0.f};
  CHECK(a.step_guarded(good) == nn::NetStatus::Ok);
  b.step(good);
  std::vector<float> before(a.output().data(), a.output().data() + 5);
  CHECK(a.step_guarded(nan_in) == nn::NetStatus::RejectedInput);
  CHECK(a.step_guarded(inf_in) == nn::NetStatus::RejectedInput);
  for (int i = 0; i < 5; ++i) CHECK(a.output()[i] == before[i]);
  // state untouched: the next good frame gives exactly what an instance that never saw NaN gives
  CHECK(a.step_guarded(good) == nn::NetStatus::Ok);
  const float* yb = b.step(good);
  for (int i = 0; i < 5; ++i) CHECK(a.output()[i] == yb[i]);
  // a corrupted hidden state (NaN) is detected from the output and reset
  std::vector<float> last(a.output().data(), a.output().data() + 5);
  a.state().h[0][2] = std::numeric_limits<float>::quiet_NaN();
  CHECK(a.step_guarded(good) == nn::NetStatus::StateReset);
  for (int i = 0; i < 5; ++i) CHECK(a.output()[i] == last[i]);
  for (int i = 0; i < 5; ++i) CHECK(a.state().h[0][i] == 0.f);
  CHECK(a.step_guarded(good) == nn::NetStatus::Ok);
  for (int i = 0; i < 5; ++i) CHECK(std::isfinite(a.output()[i]));
}
