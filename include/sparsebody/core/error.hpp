// Errors raised at load time (weights, models, files). Per-step paths never throw: they report
// problems through return values (see each step's Status), so only loaders use these types.
#pragma once
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

namespace sparsebody {

// At most `max_chars` of some offending content, on one line: control characters (newlines,
// tabs, NUL, ...) shown as spaces, and a longer text cut in the middle, keeping its start and its
// end, with the number of characters left out. Loaders quote file content through this.
inline std::string excerpt(const std::string& s, std::size_t max_chars = 200) {
  std::string out;
  auto put = [&out](char c) { out += (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) ? ' ' : c; };
  if (s.size() <= max_chars) {
    for (char c : s) put(c);
    return out;
  }
  const std::size_t tail = max_chars / 4, head = max_chars - tail;
  for (std::size_t i = 0; i < head; ++i) put(s[i]);
  out += " [... " + std::to_string(s.size() - head - tail) + " characters ...] ";
  for (std::size_t i = s.size() - tail; i < s.size(); ++i) put(s[i]);
  return out;
}

// A file or document could not be loaded. what() names the file, then the place (tensor, line,
// field) and what was expected, e.g. "model.json: tensor 'gru.weight_hh_l0': expected shape
// [768, 256], got [768, 128]". It is always one line of at most ~400 characters: the detail goes
// through excerpt(), so no message can carry a file's content (base64 tensors, binary garbage).
class LoadError : public std::runtime_error {
 public:
  static constexpr std::size_t kMaxDetail = 320;

  LoadError(const std::string& source, const std::string& detail)
      : std::runtime_error(compose(source, detail)), source_(excerpt(source, 160)), detail_(excerpt(detail, kMaxDetail)) {}

  // The file at `path` cannot be opened: says why (errno), e.g. "No such file or directory".
  static LoadError cannot_open(const std::string& path, int err = errno) {
    return LoadError(path, std::string("cannot open file (") + (err ? std::strerror(err) : "unknown reason") + ")");
  }

  const std::string& source() const noexcept { return source_; }
  const std::string& detail() const noexcept { return detail_; }

 private:
  static std::string compose(const std::string& source, const std::string& detail) {
    const std::string d = excerpt(detail, kMaxDetail);
    return source.empty() ? d : excerpt(source, 160) + ": " + d;
  }
  std::string source_;
  std::string detail_;
};

}  // namespace sparsebody
