// Counts heap allocations: a test program that links tests/support/allocation_counter.cpp has
// the global allocation functions replaced by counting ones (step() allocates
// nothing; the allocation tests check it).
#pragma once

namespace limber::testing {

/// Allocations (every operator new) made by this program so far.
long allocation_count();

}  // namespace limber::testing
