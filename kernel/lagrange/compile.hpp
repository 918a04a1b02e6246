// compile_lagrange(Model, LagrangeOptions) -> LagrangeState: rigid bodies and joint constraints.
#pragma once

#include "limber/kernel/lagrange/lagrange_state.hpp"
#include "limber/kernel/model/model.hpp"

namespace limber {

/// Builds the Lagrange-multiplier state of `model`: the rigid scene (compile_rigid_scene,
/// kernel/rigid/rigid_scene.hpp), each joint and gear as its constraint rows
/// (kernel/lagrange/constraints.hpp), ordered for Baraff's tree solver when they form no loop
/// (the sparse solver otherwise; options.solver may force either). Throws ModelError when the model is invalid, or
/// when the tree solver is forced on a graph with a loop (naming the joint that closes it).
LagrangeState compile_lagrange(const Model& model, const LagrangeOptions& options = {});

}  // namespace limber
