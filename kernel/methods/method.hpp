// The one method dispatch: which of the four methods, its options, and its compiled state, with
// each method's answers to the calls of method_contract.hpp (its step.hpp and bodies.hpp). The
// World compiles through compile_method and steps each state with limber::step(state, dt); the
// command line, the viewer and the studies step through the World (kernel/world/world.hpp).
#pragma once

#include <cstdint>
#include <string_view>
#include <variant>

#include "limber/kernel/featherstone/bodies.hpp"
#include "limber/kernel/featherstone/featherstone_state.hpp"
#include "limber/kernel/featherstone/step.hpp"
#include "limber/kernel/lagrange/bodies.hpp"
#include "limber/kernel/lagrange/lagrange_state.hpp"
#include "limber/kernel/lagrange/step.hpp"
#include "limber/kernel/model/method_settings.hpp"
#include "limber/kernel/model/model.hpp"
#include "limber/kernel/model/options.hpp"
#include "limber/kernel/particles/verlet_state.hpp"
#include "limber/kernel/springs/bodies.hpp"
#include "limber/kernel/springs/spring_state.hpp"
#include "limber/kernel/springs/step.hpp"
#include "limber/kernel/verlet/bodies.hpp"
#include "limber/kernel/verlet/step.hpp"

namespace limber {

/// Any method's compiled state.
using MethodState = std::variant<VerletState<double>, VerletState<float>, SpringState, LagrangeState, FeatherstoneState>;

/// Settings::release_drives_on_impact: once a ball has touched a limb in the last step, every
/// joint drive of `state` goes limp (stiffness and damping 0). Call after each step (the World
/// and the command line do). Returns true on the step that released them.
bool release_drives_after_impact(MethodState& state);

/// Compiles `model` under `options.method`. Throws ModelError when the model is invalid or the
/// method cannot represent it, std::invalid_argument for options that do not go together.
MethodState compile_method(const Model& model, const WorldOptions& options);

}  // namespace limber
