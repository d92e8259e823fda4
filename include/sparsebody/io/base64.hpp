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

namespace sparsebody::io {

// Standard base64 with '=' padding (the encoding weights_tool writes; used by C++ exporters and tests).
inline std::string base64_encode(const std::uint8_t* data, std::size_t n) {
  static const char* a = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((n + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < n; i += 3) {
    const std::uint32_t v = std::uint32_t(data[i]) << 16 | std::uint32_t(data[i + 1]) << 8 | data[i + 2];
    out += a[v >> 18 & 63];
    out += a[v >> 12 & 63];
    out += a[v >> 6 & 63];
    out += a[v & 63];
  }
  if (i < n) {
    const std::uint32_t v = std::uint32_t(data[i]) << 16 | (i + 1 < n ? std::uint32_t(data[i + 1]) << 8 : 0u);
    out += a[v >> 18 & 63];
    out += a[v >> 12 & 63];
    out += i + 1 < n ? a[v >> 6 & 63] : '=';
    out += '=';
  }
  return out;
}

}  // namespace sparsebody::io
