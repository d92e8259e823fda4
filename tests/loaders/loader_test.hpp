// Shared helper of the loader tests.
#pragma once
#include <string>

#include "sparsebody/core/error.hpp"

namespace loader_test {

// The LoadError message f() raises, or "(no error)".
template <class F>
std::string load_error(F&& f) {
  try {
    f();
  } catch (const sparsebody::LoadError& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace loader_test
