// Many users' LoBSTr avatars stepped in one call (a social scene: 10-50 avatars, one weight set).
// N LoBSTrPipeline instances share the weights; per frame each does its own sanitising,
// calibration, features, contacts and IK, and their networks run together (forward_batch), so
// each weight matrix is read once per frame for all N instead of N times.
//
//   auto w = avatar::LoBSTrCompact::load("lobstr_compact.weights.json");
//   avatar::LoBSTrBatch<avatar::LoBSTrCompact> crowd(w, 16);   // 16 users, allocated once
//   crowd.step(frames);                    // frames[i]: user i's tracker frame at the model rate
//   crowd[3].world();                      // user 3's pose, as LoBSTrPipeline::step would give it
//
// Every user's results equal a LoBSTrPipeline of its own stepped with the same frames, bit for
// bit (tests/pipeline/test_batch.cpp), float, f16 and int8 storage (int8 shares weight loads with
// the VNNI kernels only: nn/int8.hpp gemv_batch_q8). Model-rate frames: the caller resamples, as for LoBSTrPipeline::step
// (frame times still matter: the sanitiser sees them). Streaming mode only (Window mode replays
// a second of frames per step and gains nothing from sharing). step() never allocates, throws
// or locks.
#pragma once
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "sparsebody/avatar/lobstr_pipeline.hpp"
#include "sparsebody/nn/panel_matrix.hpp"

namespace sparsebody::avatar {

template <class Pipeline>
class LoBSTrBatch {
 public:
  using Net = typename Pipeline::Net;
  using T = typename Net::scalar;
  using Weights = typename Pipeline::Weights;

  // n users, 1 <= n <= nn::kBatchMax (64); cfg as for each LoBSTrPipeline, mode Streaming.
  LoBSTrBatch(std::shared_ptr<const Weights> w, int n, LoBSTrConfig cfg = {}) : weights_(std::move(w)) {
    if (n < 1 || n > nn::kBatchMax)
      throw std::invalid_argument("LoBSTrBatch: " + std::to_string(n) + " users, expected 1.." + std::to_string(nn::kBatchMax));
    if (cfg.mode != RunMode::Streaming) throw std::invalid_argument("LoBSTrBatch: Streaming mode only");
    for (int i = 0; i < n; ++i) users_.push_back(std::make_unique<Pipeline>(weights_, cfg));
    io_ = std::make_unique<IO[]>(static_cast<std::size_t>(n));
  }

  int size() const noexcept { return static_cast<int>(users_.size()); }
  Pipeline& operator[](int i) noexcept { return *users_[static_cast<std::size_t>(i)]; }
  const Pipeline& operator[](int i) const noexcept { return *users_[static_cast<std::size_t>(i)]; }

  // One model frame of every user: frames[i] is user i's; restart (optional) as step()'s.
  void step(const trackers::TrackerFrame* frames, const bool* restart = nullptr) noexcept {
    const auto& w = *weights_;
    typename Net::State* s[nn::kBatchMax];
    const T* xin[nn::kBatchMax];
    T* y[nn::kBatchMax];
    int who[nn::kBatchMax];
    int m = 0;
    for (int i = 0; i < size(); ++i) {
      Pipeline& p = *users_[static_cast<std::size_t>(i)];
      const T* x = p.begin_step(frames[i], restart != nullptr && restart[i]);
      if (!x) continue;  // not usable: that user's frame is done
      T* in = io_[i].input.data();
      if (w.input_mean()) {  // as nn::Network::step, so the results match it bit for bit
        for (int k = 0; k < Net::in_size; ++k) in[k] = (x[k] - w.input_mean()[k]) * w.input_inv_std()[k];
      } else {
        for (int k = 0; k < Net::in_size; ++k) in[k] = x[k];
      }
      s[m] = &p.network().state();
      xin[m] = in;
      y[m] = io_[i].output.data();
      who[m++] = i;
    }
    if (m > 0) Net::forward_batch(w.params(), s, m, xin, y);
    for (int k = 0; k < m; ++k) {
      if (w.output_std())
        for (int j = 0; j < Net::out_size; ++j) y[k][j] = y[k][j] * w.output_std()[j] + w.output_mean()[j];
      users_[static_cast<std::size_t>(who[k])]->end_step(y[k]);
    }
  }

 private:
  struct IO {
    nn::PaddedVector<T, Net::in_size> input;
    nn::PaddedVector<T, Net::out_size> output;
  };
  std::shared_ptr<const Weights> weights_;
  std::vector<std::unique_ptr<Pipeline>> users_;
  std::unique_ptr<IO[]> io_;
};

}  // namespace sparsebody::avatar
