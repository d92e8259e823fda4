// Shared checks of the fuzz harnesses.
#pragma once
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

// Keeps a result alive so the optimiser cannot drop the work.
inline void consume(double v) {
  static volatile double sink;
  sink = v;
}

}  // namespace sparsebody_fuzz
