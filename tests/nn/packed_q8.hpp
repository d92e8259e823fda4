// A q8 matrix that owns its storage, packed as ParamBinder lays q8 weights out (nn::pack_q8): for
// kernel tests and benchmarks that call the int8 products directly.
#pragma once
#include <cstdint>
#include <vector>

#include "sparsebody/core/aligned_buffer.hpp"
#include "sparsebody/nn/int8.hpp"

namespace sparsebody_test {

struct PackedQ8 {
  sparsebody::AlignedBuffer<std::int8_t> q;
  sparsebody::AlignedBuffer<float> scale;
  sparsebody::AlignedBuffer<std::int32_t> sum;
  sparsebody::nn::PanelMatrix<float, sparsebody::nn::q8> m;
  PackedQ8(const std::vector<float>& w, int rows, int cols)  // w: rows x cols, row-major
      : q(static_cast<std::size_t>(sparsebody::nn::padded<float>(rows)) * 4 * sparsebody::nn::q8_groups(cols)),
        scale(sparsebody::nn::padded<float>(rows)),
        sum(sparsebody::nn::padded<float>(rows)) {
    sparsebody::nn::pack_q8(w.data(), rows, cols, q.data(), scale.data(), sum.data(), rows);
    m = {q.data(), scale.data(), sum.data(), rows, cols};
  }
};

}  // namespace sparsebody_test
