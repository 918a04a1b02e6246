// limber's public face in one include, <limber/limber.hpp>: the World an engine drives
// (world/world.hpp), the Model it steps (model/model.hpp: bodies, joints, colliders, balls,
// settings; Pose and Motion), the scene files that load one (scene/scene_file.hpp), each method's
// options (model/options.hpp), step statuses and reports (model/step_status.hpp), and the
// handles (in world.hpp). No solver state and no SIMD, oneTBB or sparse-solver header: those are
// the internals (world/world_internals.hpp and the method folders), which limber's own tools
// include. Box2D's include/box2d/ and MuJoCo's include/mujoco/ are the models.
#pragma once

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build
#include "limber/kernel/model/model.hpp"
#include "limber/kernel/model/options.hpp"
#include "limber/kernel/model/step_status.hpp"
#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/world/world.hpp"
