// The two choices a cache study makes about the particles (VerletOptions::layout, ::ordering),
// apart from the code that implements them: how their fields sit in memory
// (particles/interleaved_particles.hpp) and how they are numbered (graph/particle_ordering.hpp).
// A header of its own so that options can name them without the layouts' code.
#pragma once

#include <cstdint>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build

namespace limber {

/// How particle fields are laid out in memory.
enum class ParticleLayout : std::uint8_t {
  soa,    ///< one array per field (ParticleBuffer): a SIMD load takes consecutive particles
  aos,    ///< one record per particle: x y z w (16 bytes in float, 32 in double)
  aosoa,  ///< blocks of kLanesPerLine particles, one line per field inside a block
  automatic,  ///< the relaxation picks soa or aos from how its blocks load (relaxation.cpp)
};

/// How particles are numbered inside each island.
enum class ParticleOrder : std::uint8_t {
  breadth_first,          ///< from the island's root (compile's own order)
  depth_parity,           ///< red-black: even breadth-first depth, then odd (the default)
  reverse_cuthill_mckee,  ///< bandwidth-reducing
  shuffled,               ///< no locality (the baseline of the cache study)
};

}  // namespace limber
