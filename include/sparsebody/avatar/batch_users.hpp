// The users of a many-avatar batch (avatar/lobstr_batch.hpp, n3p_batch.hpp): n pipelines built
// from one weight set and, per user, the batch's IO buffers (each network's normalised input and
// output) and the model ticks of the user's last input frame (push); and BatchCalls, the calls
// every batch offers. Allocated once at construction; n outside 1..nn::kBatchMax is refused there.
#pragma once
#include <algorithm>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "sparsebody/nn/panel_matrix.hpp"
#include "sparsebody/trackers/types.hpp"

namespace sparsebody::avatar {

template <class Pipeline, class IO>
class BatchUsers {
 public:
  // who: the batch's name for the error message; args: each pipeline's constructor arguments.
  template <class... Args>
  BatchUsers(const char* who, int n, const Args&... args) {
    if (n < 1 || n > nn::kBatchMax)
      throw std::invalid_argument(std::string(who) + ": " + std::to_string(n) + " users, expected 1.." +
                                  std::to_string(nn::kBatchMax));
    for (int i = 0; i < n; ++i) users_.push_back(std::make_unique<Pipeline>(args...));
    io_ = std::make_unique<IO[]>(static_cast<std::size_t>(n));
    per_user_ = users_[0]->tracker_stream().max_ticks_per_push();
    ticks_ = std::make_unique<Tick[]>(static_cast<std::size_t>(n) * static_cast<std::size_t>(per_user_));
  }
  int size() const noexcept { return static_cast<int>(users_.size()); }
  Pipeline& operator[](int i) noexcept { return *users_[static_cast<std::size_t>(i)]; }
  const Pipeline& operator[](int i) const noexcept { return *users_[static_cast<std::size_t>(i)]; }
  IO& io(int i) noexcept { return io_[static_cast<std::size_t>(i)]; }

  // frames[i]: user i's input frame at any rate, as Pipeline::push takes it (resampling, recentre
  // and controller-swap checks in each user's own stream). Each user's frame completes 0..k model
  // ticks; round r steps, in one call run(who, m, ticks, gaps), the m users with more than r ticks:
  // ticks[k] and gaps[k] are user who[k]'s (r+1)-th tick and its restart flag; then
  // after(who[k], ticks[k], gaps[k]) for each (what Pipeline::push(f, after) calls after a step).
  // Every user sees what push(frames[i]) would do to it. Returns the number of user steps run.
  template <class Run, class After>
  int push(const trackers::TrackerFrame* frames, Run&& run, After&& after) noexcept {
    int count[nn::kBatchMax];
    int most = 0, steps = 0;
    for (int i = 0; i < size(); ++i) {
      Tick* mine = ticks_.get() + static_cast<std::size_t>(i) * static_cast<std::size_t>(per_user_);
      int& c = count[i] = 0;
      const int cap = per_user_;
      users_[static_cast<std::size_t>(i)]->push_ticks(frames[i], [mine, &c, cap](const trackers::TrackerFrame& t, bool gap) {
        if (c < cap) mine[c++] = {t, gap};  // cap is the resampler's bound: never reached
      });
      most = std::max(most, c);
    }
    for (int r = 0; r < most; ++r) {
      int who[nn::kBatchMax];
      const trackers::TrackerFrame* tick[nn::kBatchMax];
      bool gap[nn::kBatchMax];
      int m = 0;
      for (int i = 0; i < size(); ++i) {
        if (count[i] <= r) continue;
        const Tick& t = ticks_[static_cast<std::size_t>(i) * static_cast<std::size_t>(per_user_) + static_cast<std::size_t>(r)];
        users_[static_cast<std::size_t>(i)]->before_tick();
        who[m] = i;
        tick[m] = &t.frame;
        gap[m++] = t.gap;
      }
      run(static_cast<const int*>(who), m, static_cast<const trackers::TrackerFrame* const*>(tick), static_cast<const bool*>(gap));
      for (int k = 0; k < m; ++k) after(who[k], *tick[k], gap[k]);
      steps += m;
    }
    return steps;
  }

 private:
  std::vector<std::unique_ptr<Pipeline>> users_;
  std::unique_ptr<IO[]> io_;
  struct Tick {
    trackers::TrackerFrame frame;
    bool gap;
  };
  int per_user_ = 1;               // the stream's max_ticks_per_push()
  std::unique_ptr<Tick[]> ticks_;  // n x per_user_
};

// What every batch offers (CRTP over LoBSTrBatch, N3PBatch): the users, step() on model-rate
// frames and push() on device frames. Derived has a BatchUsers users_ and
// step_users(who, m, frames, restarts), which steps users who[0..m) on frames[k] together.
template <class Derived>
class BatchCalls {
 public:
  int size() const noexcept { return self().users_.size(); }
  decltype(auto) operator[](int i) noexcept { return self().users_[i]; }
  decltype(auto) operator[](int i) const noexcept { return self().users_[i]; }

  // One model frame of every user: frames[i] is user i's; restart (optional) as each
  // pipeline's step(frame, restart).
  void step(const trackers::TrackerFrame* frames, const bool* restart = nullptr) noexcept {
    int who[nn::kBatchMax];
    const trackers::TrackerFrame* f[nn::kBatchMax];
    bool r[nn::kBatchMax];
    for (int i = 0; i < size(); ++i) who[i] = i, f[i] = frames + i, r[i] = restart != nullptr && restart[i];
    self().step_users(who, size(), f, r);
  }

  // One input frame of every user at any rate (frames[i] is user i's), as each pipeline's push:
  // each user's own stream resamples it, finds recentres and controllers in the other hands, and
  // the model ticks it completes are stepped, the users' networks together. Returns the number of
  // user steps run.
  int push(const trackers::TrackerFrame* frames) noexcept {
    return push(frames, [](int, const trackers::TrackerFrame&, bool) {});
  }
  // The same, calling after(user, tick, gap) after each user's step (as a pipeline's push(f, after)).
  template <class After>
  int push(const trackers::TrackerFrame* frames, After&& after) noexcept {
    return self().users_.push(
        frames,
        [this](const int* who, int m, const trackers::TrackerFrame* const* ticks, const bool* gaps) {
          self().step_users(who, m, ticks, gaps);
        },
        after);
  }

 private:
  Derived& self() noexcept { return static_cast<Derived&>(*this); }
  const Derived& self() const noexcept { return static_cast<const Derived&>(*this); }
};

}  // namespace sparsebody::avatar
