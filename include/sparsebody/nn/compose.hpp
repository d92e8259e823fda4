// Composition of layers into networks without per-model glue:
//   Sequential<L0, L1, ...>   output of each layer feeds the next; like torch.nn.Sequential, an
//                             unnamed child i takes its tensors under "<prefix><i>."
//   Named<kName, L>           child whose tensors live under "<prefix><kName>." (a module attribute)
//   Parallel<H0, H1, ...>     heads applied to the same input, outputs concatenated; it is a
//                             grouping, not a module: it adds nothing to its heads' names
// Names are `inline constexpr char kName[] = "gru";` objects (C++17 non-type template parameters).
// Intermediate activations live in padded buffers inside the composite's State.
#pragma once
#include <string>
#include <tuple>
#include <utility>

#include "sparsebody/nn/layer.hpp"

namespace sparsebody::nn {

template <const char* Name, typename L>
struct Named {
  using scalar = typename L::scalar;
  using layer_type = L;
  static constexpr int in_size = L::in_size;
  static constexpr int out_size = L::out_size;
  static constexpr const char* name = Name;
  using Params = typename L::Params;
  using State = typename L::State;
  static void bind(Params& p, ParamBinder<scalar>& b, const std::string& prefix) {
    L::bind(p, b, prefix + Name + ".");
  }
  static void forward(const Params& p, State& s, const scalar* x, scalar* y) noexcept { L::forward(p, s, x, y); }
  static void forward_batch(const Params& p, State* const* s, int n, const scalar* const* x, scalar* const* y) noexcept {
    L::forward_batch(p, s, n, x, y);
  }
  static void reset(State& s) noexcept { L::reset(s); }
};

namespace detail {
template <typename L>
struct is_named : std::false_type {};
template <const char* N, typename L>
struct is_named<Named<N, L>> : std::true_type {};
template <typename L>
struct is_grouping : std::false_type {};
}  // namespace detail
template <typename... Hs>
struct Parallel;
namespace detail {
template <typename... Hs>
struct is_grouping<Parallel<Hs...>> : std::true_type {};

// Prefix of child i of a Sequential: named children add their own name, groupings nothing, others
// their index (as torch.nn.Sequential does).
template <typename L>
std::string child_prefix(const std::string& prefix, std::size_t i) {
  if constexpr (is_named<L>::value || is_grouping<L>::value) return prefix;
  else return prefix + std::to_string(i) + ".";
}
}  // namespace detail

template <typename... Ls>
struct Sequential {
  static_assert(sizeof...(Ls) >= 1, "Sequential needs at least one layer");
  using Layers = std::tuple<Ls...>;
  static constexpr std::size_t N = sizeof...(Ls);
  template <std::size_t I>
  using layer = std::tuple_element_t<I, Layers>;
  using scalar = typename layer<0>::scalar;
  static constexpr int in_size = layer<0>::in_size;
  static constexpr int out_size = layer<N - 1>::out_size;

  struct Params {
    std::tuple<typename Ls::Params...> layers;
  };

 private:
  template <std::size_t... I>
  static constexpr bool sizes_chain(std::index_sequence<I...>) {
    return ((layer<I>::out_size == layer<I + 1>::in_size) && ...);
  }
  static_assert(sizes_chain(std::make_index_sequence<N - 1>{}), "Sequential: a layer's out_size differs from the next in_size");
  static_assert((std::is_same_v<typename Ls::scalar, scalar> && ...), "Sequential: mixed scalar types");

  template <std::size_t... I>
  static auto make_buffers(std::index_sequence<I...>) -> std::tuple<PaddedVector<scalar, layer<I>::out_size>...>;

 public:
  struct State {
    std::tuple<typename Ls::State...> layers;
    // Output buffer of every layer but the last (which writes the caller's buffer).
    decltype(make_buffers(std::make_index_sequence<N - 1>{})) buffers;
    template <std::size_t I>
    auto& layer_state() noexcept { return std::get<I>(layers); }
  };

  static void bind(Params& p, ParamBinder<scalar>& b, const std::string& prefix) {
    bind_each(p, b, prefix, std::make_index_sequence<N>{});
  }
  static void forward(const Params& p, State& s, const scalar* x, scalar* y) noexcept {
    forward_from<0>(p, s, x, y);
  }
  // n instances at once (nn/batch.hpp; every layer needs forward_batch): equal to n forward() calls.
  static void forward_batch(const Params& p, State* const* s, int n, const scalar* const* x, scalar* const* y) noexcept {
    batch_from<0>(p, s, n, x, y);
  }
  static void reset(State& s) noexcept { reset_each(s, std::make_index_sequence<N>{}); }

 private:
  template <std::size_t... I>
  static void bind_each(Params& p, ParamBinder<scalar>& b, const std::string& prefix, std::index_sequence<I...>) {
    (layer<I>::bind(std::get<I>(p.layers), b, detail::child_prefix<layer<I>>(prefix, I)), ...);
  }
  template <std::size_t I>
  static void forward_from(const Params& p, State& s, const scalar* x, scalar* y) noexcept {
    if constexpr (I + 1 == N) {
      layer<I>::forward(std::get<I>(p.layers), std::get<I>(s.layers), x, y);
    } else {
      scalar* out = std::get<I>(s.buffers).data();
      layer<I>::forward(std::get<I>(p.layers), std::get<I>(s.layers), x, out);
      forward_from<I + 1>(p, s, out, y);
    }
  }
  template <std::size_t I>
  static void batch_from(const Params& p, State* const* s, int n, const scalar* const* x, scalar* const* y) noexcept {
    typename layer<I>::State* ls[kBatchMax];
    for (int i = 0; i < n; ++i) ls[i] = &std::get<I>(s[i]->layers);
    if constexpr (I + 1 == N) {
      layer<I>::forward_batch(std::get<I>(p.layers), ls, n, x, y);
    } else {
      scalar* out[kBatchMax];
      for (int i = 0; i < n; ++i) out[i] = std::get<I>(s[i]->buffers).data();
      layer<I>::forward_batch(std::get<I>(p.layers), ls, n, x, out);
      batch_from<I + 1>(p, s, n, out, y);
    }
  }
  template <std::size_t... I>
  static void reset_each(State& s, std::index_sequence<I...>) {
    (layer<I>::reset(std::get<I>(s.layers)), ...);
  }
};

// Heads on one input; outputs are concatenated in order (head i starts at the sum of earlier sizes).
template <typename... Hs>
struct Parallel {
  static_assert(sizeof...(Hs) >= 1, "Parallel needs at least one head");
  using Heads = std::tuple<Hs...>;
  static constexpr std::size_t N = sizeof...(Hs);
  template <std::size_t I>
  using head = std::tuple_element_t<I, Heads>;
  using scalar = typename head<0>::scalar;
  static constexpr int in_size = head<0>::in_size;
  static constexpr int out_size = (Hs::out_size + ...);
  static_assert(((Hs::in_size == in_size) && ...), "Parallel: heads must share the input size");

  struct Params {
    std::tuple<typename Hs::Params...> heads;
  };
  struct State {
    std::tuple<typename Hs::State...> heads;
    std::tuple<PaddedVector<scalar, Hs::out_size>...> buffers;  // heads write padded buffers
  };

  static void bind(Params& p, ParamBinder<scalar>& b, const std::string& prefix) {
    bind_each(p, b, prefix, std::make_index_sequence<N>{});
  }
  static void forward(const Params& p, State& s, const scalar* x, scalar* y) noexcept {
    forward_each(p, s, x, y, std::make_index_sequence<N>{});
  }
  // n instances at once (nn/batch.hpp): each head batched, then copied out as forward() does.
  static void forward_batch(const Params& p, State* const* s, int n, const scalar* const* x, scalar* const* y) noexcept {
    batch_each(p, s, n, x, y, std::make_index_sequence<N>{});
  }
  static void reset(State& s) noexcept { reset_each(s, std::make_index_sequence<N>{}); }

 private:
  template <std::size_t I>
  static constexpr int offset() {
    int o = 0;
    std::size_t i = 0;
    ((o += (i++ < I ? Hs::out_size : 0)), ...);
    return o;
  }
  template <std::size_t... I>
  static void bind_each(Params& p, ParamBinder<scalar>& b, const std::string& prefix, std::index_sequence<I...>) {
    (head<I>::bind(std::get<I>(p.heads), b, detail::child_prefix<head<I>>(prefix, I)), ...);
  }
  template <std::size_t... I>
  static void forward_each(const Params& p, State& s, const scalar* x, scalar* y, std::index_sequence<I...>) noexcept {
    ((head<I>::forward(std::get<I>(p.heads), std::get<I>(s.heads), x, std::get<I>(s.buffers).data()),
      copy_n(std::get<I>(s.buffers).data(), head<I>::out_size, y + offset<I>())), ...);
  }
  template <std::size_t I>
  static void batch_head(const Params& p, State* const* s, int n, const scalar* const* x, scalar* const* y) noexcept {
    typename head<I>::State* hs[kBatchMax];
    scalar* out[kBatchMax];
    for (int i = 0; i < n; ++i) {
      hs[i] = &std::get<I>(s[i]->heads);
      out[i] = std::get<I>(s[i]->buffers).data();
    }
    head<I>::forward_batch(std::get<I>(p.heads), hs, n, x, out);
    for (int i = 0; i < n; ++i) copy_n(out[i], head<I>::out_size, y[i] + offset<I>());
  }
  template <std::size_t... I>
  static void batch_each(const Params& p, State* const* s, int n, const scalar* const* x, scalar* const* y,
                         std::index_sequence<I...>) noexcept {
    (batch_head<I>(p, s, n, x, y), ...);
  }
  static void copy_n(const scalar* src, int n, scalar* dst) noexcept {
    for (int i = 0; i < n; ++i) dst[i] = src[i];
  }
  template <std::size_t... I>
  static void reset_each(State& s, std::index_sequence<I...>) {
    (head<I>::reset(std::get<I>(s.heads)), ...);
  }
};

}  // namespace sparsebody::nn
