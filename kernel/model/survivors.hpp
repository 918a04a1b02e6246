// What survives a structural edit of a Model (a body, joint, collider or ball added or removed):
// for each body and ball of the edited Model, the old one it continues. Each method's
// carry_state reads it to carry positions, velocities and sleep across a recompile
// (kernel/methods/method_contract.hpp).
#pragma once

#include <cstdint>
#include <vector>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build

namespace limber {

/// One entry per new Model body, and one per new ball: the old index it continues, −1 when new.
struct Survivors {
  std::vector<std::int64_t> bodies, balls;
};

}  // namespace limber
