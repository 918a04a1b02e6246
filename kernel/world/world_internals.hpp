// What a World keeps behind its public face (world.hpp): the method's compiled state and the
// bounds its divergence check measures against. For limber's own tools (the command line, the
// viewer, the studies, tests) that read a state's observers and counters; it includes the whole
// kernel, which world.hpp does not.
#pragma once

#include "limber/kernel/methods/method.hpp"
#include "limber/kernel/metrics/divergence.hpp"
#include "limber/kernel/world/world.hpp"

namespace limber {

struct WorldInternals {
  MethodState state;
  DivergenceBounds divergence;  ///< from the start, the last structural edit or teleport
  StepReport report;            ///< the last step's: the method's, with the World's status
};

}  // namespace limber
