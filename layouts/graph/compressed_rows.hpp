// Compressed rows: many short lists in two flat arrays (the CSR layout of sparse matrices).
#pragma once

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build

namespace limber {

/// Row r holds entries[offsets[r] .. offsets[r + 1]). Shapes: offsets has rows() + 1 elements.
/// One allocation per array instead of one per row, and rows stored back to back.
template <typename T>
struct CompressedRows {
  std::vector<std::uint32_t> offsets{0};
  std::vector<T> entries;

  std::size_t rows() const { return offsets.size() - 1; }
  std::span<const T> row(std::size_t r) const { return {entries.data() + offsets[r], entries.data() + offsets[r + 1]}; }
};

/// Groups (row, value) pairs by row, keeping their order within each row (a stable counting
/// sort, O(rows + pairs)). Rows must be < `rows`.
template <typename T>
CompressedRows<T> group_by_row(std::size_t rows, const std::vector<std::pair<std::uint32_t, T>>& pairs) {
  CompressedRows<T> grouped;
  grouped.offsets.assign(rows + 1, 0);
  for (const auto& pair : pairs) ++grouped.offsets[pair.first + 1];
  for (std::size_t r = 0; r < rows; ++r) grouped.offsets[r + 1] += grouped.offsets[r];
  grouped.entries.resize(pairs.size());
  std::vector<std::uint32_t> next(grouped.offsets.begin(), grouped.offsets.end() - 1);
  for (const auto& pair : pairs) grouped.entries[next[pair.first]++] = pair.second;
  return grouped;
}

}  // namespace limber
