// compile_springs(Model, SpringOptions) -> SpringState: the Model as rigid bodies and springs.
#pragma once

#include "limber/kernel/model/model.hpp"
#include "limber/kernel/springs/spring_state.hpp"

namespace limber {

/// Builds the stiff-spring state of `model` (thesis 4.4.1): the rigid scene
/// (compile_rigid_scene, kernel/rigid/rigid_scene.hpp), and each spherical joint as a zero-length
/// spring with damping between its inboard and outboard anchors (a world anchor stays fixed), k
/// and c from `options`, else the joint's, else options.defaults. For the implicit integrator the
/// sparse pattern is built and analysed once (AMD ordering).
/// Throws ModelError when the model or the options are invalid.
SpringState compile_springs(const Model& model, const SpringOptions& options = {});

}  // namespace limber
