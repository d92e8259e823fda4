// Many users' LoBSTr avatars stepped in one call (a social scene: 10-50 avatars, one weight set).
// N LoBSTrPipeline instances share the weights; per frame each does its own sanitising,
// calibration, features, contacts and IK, and their networks run together (forward_batch), so
// each weight matrix is read once per frame for all N instead of N times.
//
//   auto w = avatar::LoBSTrCompact::load("lobstr_compact.weights.json");
//   avatar::LoBSTrBatch<avatar::LoBSTrCompact> crowd(w, 16);   // 16 users, allocated once
//   crowd.push(frames);                    // frames[i]: user i's device frame at any rate
//   crowd[3].world();                      // user 3's pose, as LoBSTrPipeline::push would give it
//
// Every user's results equal a LoBSTrPipeline of its own stepped with the same frames, bit for
// bit (tests/pipeline/test_batch.cpp), float, f16 and int8 storage (int8 shares weight loads where
// the CPU has an 8-bit dot product: nn/int8.hpp gemv_batch). push() takes device frames as
// LoBSTrPipeline::push does (each user's own resampling, recentre and controller-swap checks);
// step() takes model-rate frames as LoBSTrPipeline::step does (the caller resamples; frame times
// still matter: the sanitiser sees them). Streaming mode only (Window mode replays
// a second of frames per step and gains nothing from sharing). push() and step() never
// allocate, throw or lock.
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
class LoBSTrBatch : public BatchCalls<LoBSTrBatch<Pipeline>> {
 public:
  using Net = typename Pipeline::Net;
  using T = typename Net::scalar;
  using Weights = typename Pipeline::Weights;

  // n users, 1 <= n <= nn::kBatchMax (64); cfg as for each LoBSTrPipeline, mode Streaming.
  LoBSTrBatch(const std::shared_ptr<const Weights>& w, int n, LoBSTrConfig cfg = {})
      : users_("LoBSTrBatch", n, w, streaming_only(cfg)) {}
  // size(), operator[] (user i's pipeline), step(frames), push(frames): BatchCalls (avatar/batch_users.hpp).

 private:
  friend class BatchCalls<LoBSTrBatch>;
  // Users who[0..m) step on frames f[k] (restart r[k]), their networks in one call.
  void step_users(const int* who_in, int n, const trackers::TrackerFrame* const* f, const bool* r) noexcept {
    nn::Network<Net>* nets[nn::kBatchMax];
    const T* x[nn::kBatchMax];
    T* in[nn::kBatchMax];
    T* y[nn::kBatchMax];
    int who[nn::kBatchMax];
    int m = 0;
    for (int k = 0; k < n; ++k) {
      const int i = who_in[k];
      Pipeline& p = users_[i];
      x[m] = p.begin_step(*f[k], r[k]);
      if (!x[m]) continue;  // not usable: that user's frame is done
      nets[m] = &p.network();
      in[m] = users_.io(i).input.data();
      y[m] = users_.io(i).output.data();
      who[m++] = i;
    }
    nn::step_networks(nets, m, x, in, y);
    for (int k = 0; k < m; ++k) users_[who[k]].end_step(y[k]);
  }

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
