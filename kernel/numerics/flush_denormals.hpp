// Denormal (subnormal) floats are 10–100× slower on x86. A body coming to rest drives values
// like x − x* towards zero, through the denormal range: a float chain settling at the origin
// stepped 2.5× slower (bench/speed.md, "Float and double"). Like Jolt (FPFlushDenormals), limber
// flushes them to zero for the duration of a step; the change is limited to numbers below
// ~1e-38 (float) and ~1e-308 (double), and is the same on every thread that steps.
#pragma once

#if defined(__SSE__) || defined(__x86_64__)
#include <xmmintrin.h>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build
#endif

namespace limber {

/// Sets flush-to-zero and denormals-are-zero on this thread for its lifetime, then restores the
/// previous mode. A no-op where the instruction set offers no such switch.
class FlushDenormals {
 public:
#if defined(__SSE__) || defined(__x86_64__)
  FlushDenormals() : saved_(_mm_getcsr()) { _mm_setcsr(saved_ | kFlushToZero | kDenormalsAreZero); }
  ~FlushDenormals() { _mm_setcsr(saved_); }

 private:
  static constexpr unsigned kFlushToZero = 0x8000;       // MXCSR bit 15
  static constexpr unsigned kDenormalsAreZero = 0x0040;  // MXCSR bit 6
  unsigned saved_;
#else
  FlushDenormals() = default;
#endif
  FlushDenormals(const FlushDenormals&) = delete;
  FlushDenormals& operator=(const FlushDenormals&) = delete;
};

}  // namespace limber
