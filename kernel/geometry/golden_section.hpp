// Golden-section search for the minimum of a unimodal function of one variable (Kiefer 1953;
// Press et al., "Numerical Recipes", 3rd ed., 10.2): each step keeps the part of the bracket
// that holds the smaller of two interior values and evaluates one new point. Used along a line,
// where a distance to a convex set is convex, so unimodal.
#pragma once

#include <cmath>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build

namespace limber {

/// Where the search stopped: the bracket [low, high] and its two interior points with their values.
struct GoldenBracket {
  double low = 0, high = 1;
  double left = 0, right = 0;
  double f_left = 0, f_right = 0;
};

/// Narrows [low, high] around the minimum of `f` for `steps` steps, or until `stop(f_left,
/// f_right)` holds (checked before each step).
template <typename F, typename Stop>
GoldenBracket golden_section(F&& f, double low, double high, int steps, Stop&& stop) {
  const double ratio = 0.5 * (std::sqrt(5.0) - 1);
  GoldenBracket b{low, high, high - ratio * (high - low), low + ratio * (high - low), 0, 0};
  b.f_left = f(b.left), b.f_right = f(b.right);
  for (int k = 0; k < steps && !stop(b.f_left, b.f_right); ++k) {
    if (b.f_left <= b.f_right) {
      b.high = b.right, b.right = b.left, b.f_right = b.f_left;
      b.left = b.high - ratio * (b.high - b.low), b.f_left = f(b.left);
    } else {
      b.low = b.left, b.left = b.right, b.f_left = b.f_right;
      b.right = b.low + ratio * (b.high - b.low), b.f_right = f(b.right);
    }
  }
  return b;
}

}  // namespace limber
