// Measuring a damped oscillation from a sampled trajectory: the joint drive tests' damping ratio.
#pragma once

#include <cmath>
#include <numbers>
#include <vector>

namespace limber::testing {

/// Successive maxima of x(t) (interior samples only).
inline std::vector<double> maxima(const std::vector<double>& x) {
  std::vector<double> peaks;
  for (std::size_t k = 1; k + 1 < x.size(); ++k) {
    if (x[k] > x[k - 1] && x[k] >= x[k + 1]) peaks.push_back(x[k]);
  }
  return peaks;
}

/// The damping ratio of a decaying oscillation from two successive maxima a period apart: the
/// logarithmic decrement δ = ln(first/second), ζ = δ/√(4π² + δ²).
inline double damping_ratio(double first, double second) {
  const double decrement = std::log(first / second);
  return decrement / std::sqrt(4 * std::numbers::pi * std::numbers::pi + decrement * decrement);
}

}  // namespace limber::testing
