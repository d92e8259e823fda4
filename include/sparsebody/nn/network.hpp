// A network with loaded weights, and instances of it that run steps.
//
//   auto weights = nn::NetworkWeights<Net>::load("model.json", "lobstr");   // once, may throw LoadError
//   nn::Network<Net> a(weights), b(weights);    // any number of instances/threads share the weights
//   const float* y = a.step(x);                 // per frame: no allocation, no exception, no lock
//
// NetworkWeights owns the WeightStore (allocated once at load, immutable afterwards) plus the
// optional input/output normalisation: x_n = (x - input_mean) / input_std, y = y_n * output_std +
// output_mean. Network owns only its State (hidden states, scratch), itself allocated once at
// construction so that even 1024-wide GRU instances never sit on the caller's stack.
#pragma once
#include <cmath>
#include <memory>
#include <string>
#include <string_view>

#include <Eigen/Core>

#include "sparsebody/io/weights_json.hpp"
#include "sparsebody/nn/param_binder.hpp"

namespace sparsebody::nn {

template <class Net>
class NetworkWeights {
 public:
  using T = typename Net::scalar;
  using Params = typename Net::Params;

  // Loads and validates a weights file; `kind` is the model kind the caller expects.
  static std::shared_ptr<const NetworkWeights> load(const std::string& path, std::string_view kind) {
    return from_document(io::read_weights_file(path), kind);
  }
  static std::shared_ptr<const NetworkWeights> from_string(const std::string& text, std::string_view kind,
                                                           const std::string& source = "<string>") {
    return from_document(io::parse_weights(text, source), kind);
  }
  static std::shared_ptr<const NetworkWeights> from_document(io::WeightsDocument doc, std::string_view kind) {
    std::shared_ptr<NetworkWeights> w(new NetworkWeights());
    io::ModelInfo& info = doc.info;
    const std::string& src = info.source;
    if (info.kind != kind)
      throw LoadError(src, "model kind '" + info.kind + "' cannot be loaded as '" + std::string(kind) + "'");
    if (info.input_size != Net::in_size || info.output_size != Net::out_size)
      throw LoadError(src, "meta.input_size/output_size " + std::to_string(info.input_size) + "/" +
                               std::to_string(info.output_size) + " do not match the network (" +
                               std::to_string(Net::in_size) + "/" + std::to_string(Net::out_size) + ")");
    ParamBinder<T> binder(doc.tensors, w->store_);
    Net::bind(w->params_, binder, "");
    doc.tensors.check_all_used();
    w->bind_normalization(info.normalization);
    w->info_ = std::move(info);
    return w;
  }

  const Params& params() const noexcept { return params_; }
  const io::ModelInfo& info() const noexcept { return info_; }
  // Parameter bytes one step streams (the memory-traffic floor of a step).
  std::size_t bytes() const noexcept { return store_.bytes(); }
  const WeightStore<T>& store() const noexcept { return store_; }
  const T* input_mean() const noexcept { return in_mean_; }
  const T* input_inv_std() const noexcept { return in_inv_std_; }
  const T* output_mean() const noexcept { return out_mean_; }
  const T* output_std() const noexcept { return out_std_; }

 private:
  NetworkWeights() = default;

  void bind_normalization(io::TensorTable& t) {
    auto pair = [&](const char* mean, const char* std, int n, const T*& m, const T*& s, bool invert) {
      const bool has_m = t.tensors().count(mean) != 0, has_s = t.tensors().count(std) != 0;
      if (has_m != has_s)
        throw LoadError(t.source(), std::string("normalization: '") + (has_m ? mean : std) + "' given without '" +
                                        (has_m ? std : mean) + "'");
      if (!has_m) return;
      const io::Tensor& tm = t.take(mean, {n});
      const io::Tensor& ts = t.take(std, {n});
      T* pm = store_.allocate(static_cast<std::size_t>(n));
      T* ps = store_.allocate(static_cast<std::size_t>(n));
      for (int i = 0; i < n; ++i) {
        if (!(ts.values[i] > 0))
          throw LoadError(t.source(), std::string("normalization '") + std + "': value at index " + std::to_string(i) +
                                          " must be > 0, got " + std::to_string(ts.values[i]));
        pm[i] = static_cast<T>(tm.values[i]);
        ps[i] = invert ? static_cast<T>(1.0 / ts.values[i]) : static_cast<T>(ts.values[i]);
      }
      m = pm;
      s = ps;
    };
    pair("input_mean", "input_std", Net::in_size, in_mean_, in_inv_std_, true);
    pair("output_mean", "output_std", Net::out_size, out_mean_, out_std_, false);
    t.check_all_used();
  }

  WeightStore<T> store_;
  Params params_{};
  io::ModelInfo info_;
  const T* in_mean_ = nullptr;
  const T* in_inv_std_ = nullptr;
  const T* out_mean_ = nullptr;
  const T* out_std_ = nullptr;
};

// What step_guarded() did with a frame.
enum class NetStatus {
  Ok,             // stepped normally
  RejectedInput,  // an input was NaN/Inf: nothing changed, output() still holds the last good output
  StateReset,     // the step produced a non-finite output (diverged state): the recurrent state was
                   // reset to zero and output() still holds the last good output
};

template <class Net>
class Network {
 public:
  using T = typename Net::scalar;
  using State = typename Net::State;
  static constexpr int in_size = Net::in_size;
  static constexpr int out_size = Net::out_size;
  using Input = Eigen::Matrix<T, in_size, 1>;
  using Output = Eigen::Matrix<T, out_size, 1>;

  explicit Network(std::shared_ptr<const NetworkWeights<Net>> weights)
      : weights_(std::move(weights)), mem_(std::make_unique<Memory>()) {}

  // One step: normalise x (in_size values), run the network, denormalise. Returns the out_size
  // outputs, valid until the next step. No allocation, no exception, no lock.
  const T* step(const T* x) noexcept {
    const NetworkWeights<Net>& w = *weights_;
    T* xin = mem_->input.data();
    if (w.input_mean()) {
      for (int i = 0; i < in_size; ++i) xin[i] = (x[i] - w.input_mean()[i]) * w.input_inv_std()[i];
    } else {
      for (int i = 0; i < in_size; ++i) xin[i] = x[i];
    }
    T* y = mem_->output.data();
    Net::forward(w.params(), mem_->state, xin, y);
    if (w.output_std())
      for (int i = 0; i < out_size; ++i) y[i] = y[i] * w.output_std()[i] + w.output_mean()[i];
    return y;
  }
  Eigen::Map<const Output> step(const Eigen::Ref<const Input>& x) noexcept {
    return Eigen::Map<const Output>(step(x.data()));
  }

  // step() with the bad-input policy applied: a frame with a non-finite input is not fed to the
  // network (a NaN would poison the hidden state for good), and a non-finite result resets the
  // recurrent state; in both cases output() keeps the last good output (zeros before any).
  NetStatus step_guarded(const T* x) noexcept {
    for (int i = 0; i < in_size; ++i)
      if (!std::isfinite(x[i])) return NetStatus::RejectedInput;
    T* last = mem_->last_good.data();
    const T* y = step(x);
    bool finite = true;
    for (int i = 0; i < out_size; ++i) finite &= static_cast<bool>(std::isfinite(y[i]));
    if (!finite) {
      reset();
      for (int i = 0; i < out_size; ++i) mem_->output.v[i] = last[i];
      return NetStatus::StateReset;
    }
    for (int i = 0; i < out_size; ++i) last[i] = y[i];
    return NetStatus::Ok;
  }
  // Outputs of the last step.
  Eigen::Map<const Output> output() const noexcept { return Eigen::Map<const Output>(mem_->output.data()); }

  // Clears recurrent state (hidden states to zero), e.g. after a tracking gap.
  void reset() noexcept { Net::reset(mem_->state); }
  // Direct access to the state (e.g. GRU hidden states) to read, save or set it.
  State& state() noexcept { return mem_->state; }
  const State& state() const noexcept { return mem_->state; }
  const NetworkWeights<Net>& weights() const noexcept { return *weights_; }

 private:
  struct Memory {
    State state{};
    PaddedVector<T, in_size> input;
    PaddedVector<T, out_size> output;
    PaddedVector<T, out_size> last_good;  // for step_guarded()
  };
  std::shared_ptr<const NetworkWeights<Net>> weights_;
  std::unique_ptr<Memory> mem_;
};

}  // namespace sparsebody::nn
