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
/// The same into `grouped`, reusing its storage: allocates only when it outgrows what it held.
template <typename T>
void group_by_row_into(CompressedRows<T>& grouped, std::size_t rows, const std::vector<std::pair<std::uint32_t, T>>& pairs) {
  // Counts go two places on: after the prefix sums offsets[r + 1] is where row r starts, and
  // placing moves it to where row r ends, which is where row r + 1 starts.
  grouped.offsets.assign(rows + 2, 0);
  for (const auto& pair : pairs) ++grouped.offsets[pair.first + 2];
  for (std::size_t r = 2; r < rows + 2; ++r) grouped.offsets[r] += grouped.offsets[r - 1];
  grouped.entries.resize(pairs.size());
  for (const auto& pair : pairs) grouped.entries[grouped.offsets[pair.first + 1]++] = pair.second;
  grouped.offsets.pop_back();
}

template <typename T>
CompressedRows<T> group_by_row(std::size_t rows, const std::vector<std::pair<std::uint32_t, T>>& pairs) {
  CompressedRows<T> grouped;
  group_by_row_into(grouped, rows, pairs);
  return grouped;
}

}  // namespace limber
