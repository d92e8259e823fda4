// The shipped Neural3Points predictor weights (SPARSEBODY_N3P_WEIGHTS, set by bench/*.cmake), loaded
// once per pipeline type for the benchmarks of that folder; null when the files are missing, so the
// benchmark can skip with an error instead of aborting the whole binary.
#pragma once
#include <exception>

template <class P>
const typename P::Weights* n3p_default_weights() {
  static typename P::Weights w;
  static bool tried = false, ok = false;
  if (!tried) {
    tried = true;
    try {
      w = P::load(SPARSEBODY_N3P_WEIGHTS);
      ok = true;
    } catch (const std::exception&) {
    }
  }
  return ok ? &w : nullptr;
}
