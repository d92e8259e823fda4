// The users of a many-avatar batch (avatar/lobstr_batch.hpp, n3p_batch.hpp): n pipelines built
// from one weight set and, per user, the batch's IO buffers (each network's normalised input and
// output). Allocated once at construction; n outside 1..nn::kBatchMax is refused there.
#pragma once
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "sparsebody/nn/panel_matrix.hpp"

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
  }
  int size() const noexcept { return static_cast<int>(users_.size()); }
  Pipeline& operator[](int i) noexcept { return *users_[static_cast<std::size_t>(i)]; }
  const Pipeline& operator[](int i) const noexcept { return *users_[static_cast<std::size_t>(i)]; }
  IO& io(int i) noexcept { return io_[static_cast<std::size_t>(i)]; }

 private:
  std::vector<std::unique_ptr<Pipeline>> users_;
  std::unique_ptr<IO[]> io_;
};

}  // namespace sparsebody::avatar
