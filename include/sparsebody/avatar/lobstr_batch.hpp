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

#include "sparsebody/avatar/batch_users.hpp"
#include "sparsebody/avatar/lobstr_pipeline.hpp"
#include "sparsebody/nn/batch.hpp"

namespace sparsebody::avatar {

template <class Pipeline>
class LoBSTrBatch {
 public:
  using Net = typename Pipeline::Net;
  using T = typename Net::scalar;
  using Weights = typename Pipeline::Weights;

  // n users, 1 <= n <= nn::kBatchMax (64); cfg as for each LoBSTrPipeline, mode Streaming.
  LoBSTrBatch(const std::shared_ptr<const Weights>& w, int n, LoBSTrConfig cfg = {})
      : users_("LoBSTrBatch", n, w, streaming_only(cfg)) {}

  int size() const noexcept { return users_.size(); }
  Pipeline& operator[](int i) noexcept { return users_[i]; }
  const Pipeline& operator[](int i) const noexcept { return users_[i]; }

  // One model frame of every user: frames[i] is user i's; restart (optional) as step()'s.
  void step(const trackers::TrackerFrame* frames, const bool* restart = nullptr) noexcept {
    nn::Network<Net>* nets[nn::kBatchMax];
    const T* x[nn::kBatchMax];
    T* in[nn::kBatchMax];
    T* y[nn::kBatchMax];
    int who[nn::kBatchMax];
    int m = 0;
    for (int i = 0; i < size(); ++i) {
      Pipeline& p = users_[i];
      x[m] = p.begin_step(frames[i], restart != nullptr && restart[i]);
      if (!x[m]) continue;  // not usable: that user's frame is done
      nets[m] = &p.network();
      in[m] = users_.io(i).input.data();
      y[m] = users_.io(i).output.data();
      who[m++] = i;
    }
    nn::step_networks(nets, m, x, in, y);
    for (int k = 0; k < m; ++k) users_[who[k]].end_step(y[k]);
  }

 private:
  struct IO {
    nn::PaddedVector<T, Net::in_size> input;
    nn::PaddedVector<T, Net::out_size> output;
  };
  static const LoBSTrConfig& streaming_only(const LoBSTrConfig& cfg) {
    if (cfg.mode != RunMode::Streaming) throw std::invalid_argument("LoBSTrBatch: Streaming mode only");
    return cfg;
  }
  BatchUsers<Pipeline, IO> users_;
};

}  // namespace sparsebody::avatar
