// Errors raised at load time (weights, models, files). Per-step paths never throw: they report
// problems through return values (see each step's Status), so only loaders use these types.
#pragma once
#include <stdexcept>
#include <string>

namespace sparsebody {

// A file or document could not be loaded. what() names the file, then the place (tensor, line,
// field) and what was expected, e.g. "model.json: tensor 'gru.weight_hh_l0': expected shape
// [768, 256], got [768, 128]".
class LoadError : public std::runtime_error {
 public:
  LoadError(const std::string& source, const std::string& detail)
      : std::runtime_error(source.empty() ? detail : source + ": " + detail),
        source_(source), detail_(detail) {}
  const std::string& source() const noexcept { return source_; }
  const std::string& detail() const noexcept { return detail_; }

 private:
  std::string source_;
  std::string detail_;
};

}  // namespace sparsebody
