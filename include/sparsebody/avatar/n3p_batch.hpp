// Many users' Neural3Points direct-mode avatars stepped in one call (a social scene, one weight
// set): N N3PPipeline instances share the three predictors' weights; per frame each does its own
// sanitising, calibration and IK, and each of G_sig, G_lo and G_up runs once for all N users
// (forward_batch), so each weight matrix is read once per frame instead of N times.
//
//   auto w = avatar::N3PDirect::load("examples/weights/n3p");
//   avatar::N3PBatch<avatar::N3PDirect> crowd(w, 16);
//   crowd.push(frames);                    // frames[i]: user i's device frame at any rate
//   crowd[3].world();                      // user 3's pose, as N3PPipeline::push would give it
//
// Every user's results equal an N3PPipeline of its own stepped with the same frames, bit for bit
// (tests/n3p/test_batch.cpp), float, f16 and int8 storage. push() takes device frames as
// N3PPipeline::push does (each user's own resampling, recentre and controller-swap checks), step()
// model-rate frames as N3PPipeline::step does (the caller resamples). Neither allocates, throws or
// locks.
#pragma once
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "sparsebody/avatar/batch_users.hpp"
#include "sparsebody/avatar/n3p_direct.hpp"
#include "sparsebody/nn/batch.hpp"

namespace sparsebody::avatar {

template <class Pipeline>
class N3PBatch : public BatchCalls<N3PBatch<Pipeline>> {
 public:
  using Predictor = std::remove_reference_t<decltype(std::declval<Pipeline&>().predictor())>;
  using SigNet = typename Predictor::SigNet;
  using LoNet = typename Predictor::LoNet;
  using UpNet = typename Predictor::UpNet;
  using T = typename SigNet::scalar;
  using Weights = typename Pipeline::Weights;

  // n users, 1 <= n <= nn::kBatchMax (64); cfg as for each N3PPipeline.
  N3PBatch(const Weights& w, int n, N3PConfig cfg = {}) : users_("N3PBatch", n, w, cfg) {}
  // size(), operator[] (user i's pipeline), step(frames), push(frames): BatchCalls (avatar/batch_users.hpp).

 private:
  friend class BatchCalls<N3PBatch>;
  // Users who[0..m) step on frames f[k] (restart r[k]); G_sig, G_lo and G_up each run once for all.
  void step_users(const int* users, int n, const trackers::TrackerFrame* const* f, const bool* r) noexcept {
    int who[nn::kBatchMax];
    int m = 0;
    for (int k = 0; k < n; ++k)
      if (users_[users[k]].begin_step(*f[k], r[k])) who[m++] = users[k];
    if (m == 0) return;
    nn::Network<SigNet>* sig[nn::kBatchMax];
    nn::Network<LoNet>* lo[nn::kBatchMax];
    nn::Network<UpNet>* up[nn::kBatchMax];
    const T* x[nn::kBatchMax];
    T* in[nn::kBatchMax];
    T* y[nn::kBatchMax];
    for (int k = 0; k < m; ++k) {
      Predictor& p = users_[who[k]].predictor();
      sig[k] = &p.signal_network();
      lo[k] = &p.lower_network();
      up[k] = &p.upper_network();
      x[k] = p.begin_input();
    }
    // G_sig, then G_lo, then G_up, each once for the m users; the phases in between per user.
    for (int k = 0; k < m; ++k) in[k] = users_.io(who[k]).sig_in.data(), y[k] = users_.io(who[k]).sig_out.data();
    nn::step_networks(sig, m, x, in, y);
    for (int k = 0; k < m; ++k) x[k] = users_[who[k]].predictor().after_signal(y[k]);
    for (int k = 0; k < m; ++k) in[k] = users_.io(who[k]).lo_in.data(), y[k] = users_.io(who[k]).lo_out.data();
    nn::step_networks(lo, m, x, in, y);
    for (int k = 0; k < m; ++k) x[k] = users_[who[k]].predictor().after_lower(y[k]);
    for (int k = 0; k < m; ++k) in[k] = users_.io(who[k]).up_in.data(), y[k] = users_.io(who[k]).up_out.data();
    nn::step_networks(up, m, x, in, y);
    for (int k = 0; k < m; ++k) {
      Pipeline& u = users_[who[k]];
      u.end_step(u.predictor().finish(y[k]));
    }
  }

  struct IO {  // per user: each network's normalised input and output (padded)
    nn::PaddedVector<T, SigNet::in_size> sig_in;
    nn::PaddedVector<T, SigNet::out_size> sig_out;
    nn::PaddedVector<T, LoNet::in_size> lo_in;
    nn::PaddedVector<T, LoNet::out_size> lo_out;
    nn::PaddedVector<T, UpNet::in_size> up_in;
    nn::PaddedVector<T, UpNet::out_size> up_out;
  };
  BatchUsers<Pipeline, IO> users_;
};

}  // namespace sparsebody::avatar
