// Denormal (subnormal) floats are 10–100× slower on x86. A body coming to rest drives values
// like x − x* towards zero, through the denormal range: a float chain settling at the origin
// stepped 2.5× slower (bench/speed.md, "Float and double"). Like Jolt (FPFlushDenormals), limber
// flushes them to zero for the duration of a step; the change is limited to numbers below
// ~1e-38 (float) and ~1e-308 (double). The thread that steps sets it; a block another thread
// runs for it takes the stepping thread's mode (UseFloatingPointMode, threading/block_runner),
// so 1 and 2 threads compute alike.
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

/// This thread's floating-point mode (x86: MXCSR: rounding, flush-to-zero, denormals-are-zero);
/// 0 where the instruction set has none.
inline unsigned floating_point_mode() {
#if defined(__SSE__) || defined(__x86_64__)
  return _mm_getcsr();
#else
  return 0;
#endif
}

/// Sets `mode` (floating_point_mode() of another thread) on this thread for its lifetime, then
/// restores this thread's own: a block a helper runs computes as the thread that asked for it.
class UseFloatingPointMode {
 public:
#if defined(__SSE__) || defined(__x86_64__)
  explicit UseFloatingPointMode(unsigned mode) : saved_(_mm_getcsr()) {
    if (mode != saved_) _mm_setcsr(mode);
  }
  ~UseFloatingPointMode() {
    if (_mm_getcsr() != saved_) _mm_setcsr(saved_);
  }

 private:
  unsigned saved_;
#else
  explicit UseFloatingPointMode(unsigned) {}
#endif
  UseFloatingPointMode(const UseFloatingPointMode&) = delete;
  UseFloatingPointMode& operator=(const UseFloatingPointMode&) = delete;
};

}  // namespace limber
