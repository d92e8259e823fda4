// Shared checks of the fuzz harnesses.
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace sparsebody_fuzz {

// Every error is one line of bounded length (the loaders' standard: file, place, what was
// expected, at most ~200 characters of the offending content).
inline void check_message(const char* what) {
  const std::size_t n = std::strlen(what);
  if (n == 0 || n > 600 || std::strchr(what, '\n') || std::strchr(what, '\r')) {
    std::fprintf(stderr, "bad error message (%zu chars): %.700s\n", n, what);
    std::abort();
  }
}

// The fuzzer's bytes read in order; past the end every read is 0.
struct Bytes {
  const std::uint8_t* p;
  std::size_t n, i = 0;
  bool more() const { return i < n; }
  std::uint8_t u8() { return i < n ? p[i++] : 0; }
  float unit() { return u8() / 255.0f; }  // [0, 1]
};

// Keeps a result alive so the optimiser cannot drop the work.
inline void consume(double v) {
  static volatile double sink;
  sink = v;
}

}  // namespace sparsebody_fuzz
