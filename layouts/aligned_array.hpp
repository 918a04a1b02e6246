// Aligned, padded arrays: the storage under every structure-of-arrays buffer in limber.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include <xsimd/memory/xsimd_aligned_allocator.hpp>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build

namespace limber {

/// Alignment of every buffer array, in bytes: one cache line, and the width of an AVX-512
/// register, so a SIMD load at any multiple of the lane count is aligned.
inline constexpr std::size_t kBufferAlignment = 64;

/// A std::vector whose data starts on a kBufferAlignment boundary (xsimd's allocator).
template <typename T>
using AlignedArray = std::vector<T, xsimd::aligned_allocator<T, kBufferAlignment>>;

/// How many elements of T fill one aligned line (16 floats, 8 doubles, 16 uint32). Arrays are
/// padded to a multiple of this whatever the build's SIMD width, so the layout, and therefore the
/// results, do not depend on the instruction set.
template <typename T>
inline constexpr std::size_t kLanesPerLine = kBufferAlignment / sizeof(T);

/// Smallest multiple of `lanes` that is >= count.
constexpr std::size_t padded_size(std::size_t count, std::size_t lanes) {
  return (count + lanes - 1) / lanes * lanes;
}

/// 64-bit FNV-1a over raw bytes; used to fingerprint buffers for determinism checks.
inline std::uint64_t fnv1a(const void* data, std::size_t bytes, std::uint64_t hash = 14695981039346656037ull) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t k = 0; k < bytes; ++k) {
    hash ^= p[k];
    hash *= 1099511628211ull;
  }
  return hash;
}

/// Field-list utilities. A buffer describes its arrays once, in `for_each_field(f)`, calling
/// f(name, array) for each; resizing, hashing and bitwise comparison are derived from that list
/// (MuJoCo's mjxmacro idea), so adding a field is one line.
template <typename Buffer>
std::uint64_t hash_live_elements(const Buffer& buffer) {
  std::uint64_t hash = 14695981039346656037ull;
  buffer.for_each_field([&](const char*, const auto& array) {
    using Element = typename std::decay_t<decltype(array)>::value_type;
    hash = fnv1a(array.data(), buffer.size() * sizeof(Element), hash);
  });
  return hash;
}

/// True when every live element of every field has the same bits in both buffers.
template <typename Buffer>
bool bitwise_equal(const Buffer& a, const Buffer& b) {
  if (a.size() != b.size()) return false;
  bool equal = true;
  // Both buffers list their fields in the same order; walk them in lockstep.
  std::vector<std::pair<const void*, std::size_t>> spans;
  a.for_each_field([&](const char*, const auto& array) {
    using Element = typename std::decay_t<decltype(array)>::value_type;
    spans.emplace_back(array.data(), a.size() * sizeof(Element));
  });
  std::size_t k = 0;
  b.for_each_field([&](const char*, const auto& array) {
    equal = equal && std::memcmp(spans[k].first, array.data(), spans[k].second) == 0;
    ++k;
  });
  return equal;
}

}  // namespace limber
