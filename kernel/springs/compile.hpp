// compile_springs(Model, SpringOptions) -> SpringState: the Model as rigid bodies and springs.
#pragma once

#include "limber/kernel/model/model.hpp"
#include "limber/kernel/springs/spring_state.hpp"

namespace limber {

/// Builds the stiff-spring state of `model` (thesis 4.4.1): the rigid scene
/// (compile_rigid_scene, kernel/rigid/rigid_scene.hpp), and each spherical joint as a zero-length
/// spring with damping between its inboard and outboard anchors (a world anchor stays fixed), k
/// and c from `options`, else the joint's, else options.defaults. A revolute joint is two such
/// springs, each with that k and c, between the points anchor ± ε·h of the two bodies, h the
/// hinge axis and ε a quarter of the shorter limb's length (the outboard's, to the world): they
/// hold the anchor with 2k and the axis with 2k·ε² per radian, so a bend off the hinge plane
/// rings at about the anchor's own √(k/m) (2kε²/(mL²/12) = 1.5k/m for a limb of length L about
/// its centre) and gives about gap/ε, a few times the anchor's relative gap. ε = the radius r
/// would hold the axis (ε/r)² times more softly (5 to 12 times on the armed ragdoll's knees and
/// elbows). The stiffest mode is then the limbs' twist about their own axes, at
/// √(2kε²/I_axial): it sets the explicit integrators' step on thin limbs. Universal, prismatic
/// and fixed joints and gears are refused by name. For the implicit integrator the sparse
/// pattern is built and analysed once (AMD ordering).
/// Throws ModelError when the model or the options are invalid.
SpringState compile_springs(const Model& model, const SpringOptions& options = {});

}  // namespace limber
