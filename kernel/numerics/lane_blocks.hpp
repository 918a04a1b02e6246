// Small fixed-size blocks whose entries are either numbers or SIMD lanes of numbers, for the
// arithmetic the tree elimination and SmallCholesky write once for both.
//
// A "value" is a floating-point type (float, double) or a SIMD batch of one (xsimd::batch<double>:
// one independent system per lane, the instances of one shape solved side by side). The
// arithmetic here uses only +, −, ×, ÷, sqrt and comparisons, one operation sequence per entry
// whatever the value type: with -ffp-contract=off (CMakeLists.txt) and IEEE division and sqrt
// in every lane, lane k of a batch gives the same bits as the same code on lane k's numbers.
// That is why the products below are plain loops, not Eigen expressions: Eigen sums a product
// in an order that depends on whether it can vectorize the scalar type.
//
// Storage: a block of numbers is an Eigen matrix (its users fill it with Eigen expressions);
// a block of lanes is a LaneBlock. Both are read and written through block(i, j).
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <type_traits>

#include <Eigen/Core>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build

namespace limber {

/// Rows × Cols lanes, row-major.
template <typename Value, int Rows, int Cols>
struct LaneBlock {
  std::array<Value, static_cast<std::size_t>(Rows * Cols)> entries;
  Value& operator()(int i, int j) { return entries[static_cast<std::size_t>(i * Cols + j)]; }
  const Value& operator()(int i, int j) const { return entries[static_cast<std::size_t>(i * Cols + j)]; }
  static LaneBlock Zero() {
    LaneBlock block;
    block.entries.fill(Value(0));
    return block;
  }
};

/// A Rows × Cols block of `Value`s: an Eigen matrix for numbers, a LaneBlock for lanes.
template <typename Value, int Rows, int Cols>
using Block = std::conditional_t<std::is_arithmetic_v<Value>, Eigen::Matrix<Value, Rows, Cols>, LaneBlock<Value, Rows, Cols>>;

/// Whether a comparison holds in every lane (a number's comparison is one lane).
inline bool all_lanes(bool holds) { return holds; }
template <typename Mask>
bool all_lanes(const Mask& holds) {
  return all(holds);  // xsimd::all, found by argument-dependent lookup
}

/// Lane `lane` of a value (a number is its only lane), read or written on its own: for loading
/// lanes and reading them back outside the arithmetic (tests, benchmarks, gathers).
template <typename Value>
auto get_lane(const Value& value, std::size_t lane) {
  if constexpr (std::is_arithmetic_v<Value>) {
    return value;
  } else {
    alignas(64) typename Value::value_type lanes[Value::size];
    value.store_aligned(lanes);
    return lanes[lane];
  }
}
template <typename Value, typename Number>
void set_lane(Value& value, std::size_t lane, Number number) {
  if constexpr (std::is_arithmetic_v<Value>) {
    value = number;
  } else {
    alignas(64) typename Value::value_type lanes[Value::size];
    value.store_aligned(lanes);
    lanes[lane] = number;
    value = Value::load_aligned(lanes);
  }
}

/// Loads lane k of `lanes` with the number block *instances[k], one per lane (a lane-major
/// gather per entry): instances of one shape kept one at a time, solved side by side. Every
/// entry is stored before any lane value is loaded: a load right after its lanes' stores waits
/// for them (store-to-load forwarding cannot join four stores into one load), and that wait,
/// per entry, cost as much as the elimination (tree_elimination_bench, BM_RagdollLanesPacked).
template <typename Value, int Rows, int Cols, typename Instances>
void pack_lanes(LaneBlock<Value, Rows, Cols>& lanes, const Instances& instances) {
  alignas(64) typename Value::value_type values[Rows * Cols][Value::size];
  for (std::size_t lane = 0; lane < Value::size; ++lane) {
    const auto& instance = *instances[lane];
    for (int i = 0; i < Rows; ++i) {
      for (int j = 0; j < Cols; ++j) values[i * Cols + j][lane] = instance(i, j);
    }
  }
  for (int e = 0; e < Rows * Cols; ++e) lanes.entries[static_cast<std::size_t>(e)] = Value::load_aligned(values[e]);
}

/// pack_lanes' inverse: lane k of `lanes` into *instances[k].
template <typename Value, int Rows, int Cols, typename Instances>
void unpack_lanes(const LaneBlock<Value, Rows, Cols>& lanes, const Instances& instances) {
  alignas(64) typename Value::value_type values[Rows * Cols][Value::size];
  for (int e = 0; e < Rows * Cols; ++e) lanes.entries[static_cast<std::size_t>(e)].store_aligned(values[e]);
  for (std::size_t lane = 0; lane < Value::size; ++lane) {
    auto& instance = *instances[lane];
    for (int i = 0; i < Rows; ++i) {
      for (int j = 0; j < Cols; ++j) instance(i, j) = values[i * Cols + j][lane];
    }
  }
}

}  // namespace limber
