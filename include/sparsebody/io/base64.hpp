// Standard base64 (RFC 4648, '=' padding) decoding, used for the compact tensor encoding of weights
// files: little-endian IEEE floats as base64 text is ~5x faster to load than JSON number arrays.
#pragma once
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace sparsebody::io {

// Decodes `text` into `out`; returns false (out unspecified) on any character outside the alphabet,
// a length that is not a multiple of 4, or misplaced padding.
inline bool base64_decode(std::string_view text, std::vector<std::uint8_t>& out) {
  static const auto table = [] {
    std::vector<std::int8_t> t(256, -1);
    const char* a = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    for (int i = 0; i < 64; ++i) t[static_cast<unsigned char>(a[i])] = static_cast<std::int8_t>(i);
    return t;
  }();
  out.clear();
  if (text.size() % 4 != 0) return false;
  std::size_t pad = 0;
  if (!text.empty() && text.back() == '=') pad = (text.size() >= 2 && text[text.size() - 2] == '=') ? 2 : 1;
  out.resize(text.size() / 4 * 3 - pad);
  std::size_t o = 0;
  for (std::size_t i = 0; i < text.size(); i += 4) {
    std::uint32_t v = 0;
    const bool last = i + 4 == text.size();
    for (int k = 0; k < 4; ++k) {
      const unsigned char c = static_cast<unsigned char>(text[i + k]);
      int d = table[c];
      if (c == '=' && last && k >= 4 - static_cast<int>(pad)) d = 0;
      else if (d < 0) return false;
      v = (v << 6) | static_cast<std::uint32_t>(d);
    }
    const std::uint8_t bytes[3] = {static_cast<std::uint8_t>(v >> 16), static_cast<std::uint8_t>(v >> 8),
                                   static_cast<std::uint8_t>(v)};
    for (int k = 0; k < 3 && o < out.size(); ++k) out[o++] = bytes[k];
  }
  return true;
}

}  // namespace sparsebody::io
