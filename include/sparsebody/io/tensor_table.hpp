// The tensors of a weights file, by state_dict name, as read at load time (values widened to double).
// Layers take their tensors from here by name and expected shape; anything wrong is a LoadError that
// names the file, the tensor, what was expected and what was found. After binding, leftover tensors
// are reported too, so a file never loads half-used.
#pragma once
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "sparsebody/core/error.hpp"

namespace sparsebody::io {

struct Tensor {
  std::vector<std::int64_t> shape;
  std::vector<double> values;  // row-major (C order), as PyTorch stores it
};

inline std::string shape_string(const std::vector<std::int64_t>& s) {
  std::string out = "[";
  for (std::size_t i = 0; i < s.size(); ++i) out += (i ? ", " : "") + std::to_string(s[i]);
  return out + "]";
}

class TensorTable {
 public:
  TensorTable(std::string source = {}) : source_(std::move(source)) {}

  const std::string& source() const noexcept { return source_; }
  std::map<std::string, Tensor>& tensors() noexcept { return tensors_; }
  const std::map<std::string, Tensor>& tensors() const noexcept { return tensors_; }

  // Returns the tensor `name` after checking it exists and has exactly `shape`; marks it used.
  const Tensor& take(const std::string& name, const std::vector<std::int64_t>& shape) {
    auto it = tensors_.find(name);
    if (it == tensors_.end())
      throw LoadError(source_, "missing tensor '" + name + "' (expected shape " + shape_string(shape) + ")");
    if (it->second.shape != shape)
      throw LoadError(source_, "tensor '" + name + "': expected shape " + shape_string(shape) + ", got " +
                                   shape_string(it->second.shape));
    used_.insert(name);
    return it->second;
  }

  // Throws if any tensor was never taken: the file does not describe the network being loaded.
  void check_all_used() const {
    std::string extra;
    for (const auto& kv : tensors_)
      if (!used_.count(kv.first)) extra += (extra.empty() ? "'" : ", '") + kv.first + "'";
    if (!extra.empty()) throw LoadError(source_, "unexpected tensor(s) " + extra + " not used by the network");
  }

 private:
  std::string source_;
  std::map<std::string, Tensor> tensors_;
  std::set<std::string> used_;
};

}  // namespace sparsebody::io
